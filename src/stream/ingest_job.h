// `mebake ingest` as a job: the ingest (ingest.h) plus what resuming needs — the identity
// (size, CRC-32) of every input recorded in the manifest, stdin hashed on its way in — and
// the check whether a finished ingest can be reused by a rerun (docs/resume.md).
#pragma once

#include "stream/bake_dir.h"
#include "stream/ingest.h"

#include <string>
#include <utility>
#include <vector>

namespace mebake::stream {

// The ingest options that decide the tiles, as the manifest records them.
std::vector<std::pair<std::string, std::string>> IngestOptionsRecord(const IngestOptions& opt);

// Ingests, then writes the manifest a second time with the inputs' identities and the
// options record; killed before that write, the directory counts as not ingested.
Manifest RunIngestJob(const IngestOptions& opt);

// The reason a finished ingest in opt.out_dir cannot be reused for `opt`, or "" when it
// can. Throws Error(Usage) when an input or an option changed: never mixed silently.
// Reads (and so consumes) stdin only when every other check passed.
std::string CheckIngestReusable(const IngestOptions& opt);

}  // namespace mebake::stream
