// The penumbra's grid over a polygon light (penumbra.cpp): each fan triangle t = (v0,
// v[t+1], v[t+2]) carries a barycentric grid of g cells per side (g a power of two), with
// vertices (a, b), a + b <= g. Cells are the grid's triangles at the levels g/2, g/4, ... 1
// (a cell of side s has its corners on multiples of s). Its vertex indices and the slots of
// its cells' edges, in one place so a test can check them against each other.
#pragma once

#include <cstddef>
#include <cstdint>

namespace mebake::solve {

struct PenumbraGrid {
    int g = 8;        // cells per side of a fan triangle
    size_t nt = 1;    // fan triangles
    size_t per_t() const { return size_t(g + 1) * size_t(g + 1); }
    size_t vertices() const { return nt * per_t(); }

    // Fan triangles t and t+1 share the edge v0 v[t+2]: its vertices (a, 0) in t+1 are
    // (0, a) in t (the same point, computed the same way), so they are traced once.
    size_t VertexIndex(size_t t, int a, int b) const {
        if (b == 0 && t > 0)
            return (t - 1) * per_t() + size_t(a) * size_t(g + 1);
        return t * per_t() + size_t(b) * size_t(g + 1) + size_t(a);
    }

    // A dense slot per edge of the cells: two cell edges get the same slot exactly when
    // their ends have the same two vertex indices (either way round). An edge is named by
    // its fan triangle, its doubled midpoint and its direction (along a, along b, or the
    // third): at side s its ends lie on multiples of s, so the midpoint's odd multiple of s
    // gives the side back. An edge on the line v0 v[t+2] that t and t+1 share (b = 0 in
    // t + 1) takes t's slot (a = 0 there), as VertexIndex does, but for the one from v0
    // when t + 1 >= 2: VertexIndex gives v0 of t + 1 >= 2 an index of its own (t's
    // (0, 0) slot), so that edge is not t's and keeps t + 1's slot.
    size_t EdgeSlots() const { return nt * size_t(2 * g + 1) * size_t(2 * g + 1) * 3; }
    uint32_t EdgeSlot(size_t t, int a0, int b0, int a1, int b1) const {
        int ma = a0 + a1, mb = b0 + b1, dir = b0 == b1 ? 0 : a0 == a1 ? 1 : 2;
        if (dir == 0 && b0 == 0 && t > 0 && !(t >= 2 && (a0 == 0 || a1 == 0))) {
            --t;  // (a, 0) of t is (0, a) of t - 1
            mb = ma, ma = 0, dir = 1;
        }
        const size_t w = size_t(2 * g + 1);
        return uint32_t(((t * w + size_t(mb)) * w + size_t(ma)) * 3 + size_t(dir));
    }
};

}  // namespace mebake::solve
