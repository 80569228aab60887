// libFuzzer target for the OFF reader: arbitrary bytes must give a mesh or an input
// error, never a crash, hang, huge allocation or a broken streaming contract.
#include "io/mesh_format.h"
#include "text_fuzz_sink.h"

#include <cstddef>
#include <cstdint>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    mebake::io::FuzzRead(mebake::io::ReadOff, data, size);
    return 0;
}
