// Unlinked temporary files: the disk behind the caches (core/paged_file.h,
// core/mapped_cache.h) and the spills that are read back once. Nothing is left behind,
// even after a crash: the descriptor keeps the file alive.
#pragma once

#include <string>

namespace mebake {

// `dir`, or where temporaries go when it is empty: $TMPDIR, else /tmp.
std::string TemporaryDirectory(const std::string& dir = {});

// Opens a new read-write file in `dir` (empty: $TMPDIR, else /tmp) that has no name
// (O_TMPFILE, or a unique name unlinked at once where the filesystem lacks it) and returns
// its descriptor. `what` names it in messages. Throws Error(Io).
int OpenTemporaryFile(const std::string& dir, const std::string& what);

}  // namespace mebake
