// Checks for bugs, never for user input (user input gets core/error.h).
// CHECK* are always on and print the values they compare; DCHECK* only in debug builds.
#pragma once

#include <fmt/format.h>

#include <cstdio>
#include <cstdlib>

namespace mebake::detail {
[[noreturn]] inline void CheckFailed(const char* file, int line, const std::string& what) {
    std::fprintf(stderr, "mebake: internal error at %s:%d: %s\n", file, line, what.c_str());
    std::fflush(stderr);
    std::abort();
}
}  // namespace mebake::detail

#define CHECK(cond)                                                            \
    do {                                                                       \
        if (!(cond)) [[unlikely]]                                              \
            ::mebake::detail::CheckFailed(__FILE__, __LINE__, "CHECK(" #cond ")"); \
    } while (0)

#define MEBAKE_CHECK_OP(a, b, op)                                                         \
    do {                                                                                  \
        const auto& va_ = (a);                                                            \
        const auto& vb_ = (b);                                                            \
        if (!(va_ op vb_)) [[unlikely]]                                                   \
            ::mebake::detail::CheckFailed(                                                \
                __FILE__, __LINE__,                                                       \
                fmt::format("CHECK({} " #op " {}) with {} = {}, {} = {}", #a, #b, #a, va_, \
                            #b, vb_));                                                    \
    } while (0)

#define CHECK_EQ(a, b) MEBAKE_CHECK_OP(a, b, ==)
#define CHECK_NE(a, b) MEBAKE_CHECK_OP(a, b, !=)
#define CHECK_LT(a, b) MEBAKE_CHECK_OP(a, b, <)
#define CHECK_LE(a, b) MEBAKE_CHECK_OP(a, b, <=)
#define CHECK_GT(a, b) MEBAKE_CHECK_OP(a, b, >)
#define CHECK_GE(a, b) MEBAKE_CHECK_OP(a, b, >=)

#ifdef NDEBUG
#define DCHECK(cond) ((void)0)
#define DCHECK_EQ(a, b) ((void)0)
#define DCHECK_LT(a, b) ((void)0)
#define DCHECK_LE(a, b) ((void)0)
#else
#define DCHECK(cond) CHECK(cond)
#define DCHECK_EQ(a, b) CHECK_EQ(a, b)
#define DCHECK_LT(a, b) CHECK_LT(a, b)
#define DCHECK_LE(a, b) CHECK_LE(a, b)
#endif
