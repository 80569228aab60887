// Compiled by the layering tests (tests/CMakeLists.txt) with one module's include roots and
// `-include <header of a module above it>`: the compile must fail with "No such file".
