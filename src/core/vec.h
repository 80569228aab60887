// Small fixed-size vectors for geometry in flat arrays (SoA-friendly, trivially copyable).
#pragma once

#include <fmt/format.h>

#include <cmath>
#include <cstdint>

namespace mebake {

template <typename T>
struct Vec2 {
    T x = 0, y = 0;
    constexpr Vec2() = default;
    constexpr Vec2(T x_, T y_) : x(x_), y(y_) {}
    constexpr T& operator[](int i) { return (&x)[i]; }
    constexpr const T& operator[](int i) const { return (&x)[i]; }
    constexpr Vec2 operator+(const Vec2& o) const { return {x + o.x, y + o.y}; }
    constexpr Vec2 operator-(const Vec2& o) const { return {x - o.x, y - o.y}; }
    constexpr Vec2 operator*(T s) const { return {x * s, y * s}; }
    constexpr Vec2 operator/(T s) const { return {x / s, y / s}; }
    constexpr Vec2& operator+=(const Vec2& o) { x += o.x; y += o.y; return *this; }
    constexpr Vec2& operator-=(const Vec2& o) { x -= o.x; y -= o.y; return *this; }
    constexpr Vec2& operator*=(T s) { x *= s; y *= s; return *this; }
    constexpr bool operator==(const Vec2&) const = default;
};

template <typename T>
struct Vec3 {
    T x = 0, y = 0, z = 0;
    constexpr Vec3() = default;
    constexpr Vec3(T x_, T y_, T z_) : x(x_), y(y_), z(z_) {}
    template <typename U>
    constexpr explicit Vec3(const Vec3<U>& o) : x(T(o.x)), y(T(o.y)), z(T(o.z)) {}
    constexpr T& operator[](int i) { return (&x)[i]; }
    constexpr const T& operator[](int i) const { return (&x)[i]; }
    constexpr Vec3 operator+(const Vec3& o) const { return {x + o.x, y + o.y, z + o.z}; }
    constexpr Vec3 operator-(const Vec3& o) const { return {x - o.x, y - o.y, z - o.z}; }
    constexpr Vec3 operator-() const { return {-x, -y, -z}; }
    constexpr Vec3 operator*(T s) const { return {x * s, y * s, z * s}; }
    constexpr Vec3 operator/(T s) const { return {x / s, y / s, z / s}; }
    constexpr Vec3& operator+=(const Vec3& o) { x += o.x; y += o.y; z += o.z; return *this; }
    constexpr Vec3& operator-=(const Vec3& o) { x -= o.x; y -= o.y; z -= o.z; return *this; }
    constexpr Vec3& operator*=(T s) { x *= s; y *= s; z *= s; return *this; }
    constexpr bool operator==(const Vec3&) const = default;
};

using Vec2f = Vec2<float>;
using Vec2d = Vec2<double>;
using Vec3f = Vec3<float>;
using Vec3d = Vec3<double>;

template <typename T>
constexpr Vec3<T> operator*(T s, const Vec3<T>& v) { return v * s; }
template <typename T>
constexpr T Dot(const Vec3<T>& a, const Vec3<T>& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
template <typename T>
constexpr T Dot(const Vec2<T>& a, const Vec2<T>& b) { return a.x * b.x + a.y * b.y; }
template <typename T>
constexpr Vec3<T> Cross(const Vec3<T>& a, const Vec3<T>& b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <typename T>
constexpr T Cross(const Vec2<T>& a, const Vec2<T>& b) { return a.x * b.y - a.y * b.x; }
template <typename T>
T Length(const Vec3<T>& v) { return std::sqrt(Dot(v, v)); }
template <typename T>
T Length(const Vec2<T>& v) { return std::sqrt(Dot(v, v)); }
template <typename T>
Vec3<T> Normalize(const Vec3<T>& v) {
    T l = Length(v);
    return l > 0 ? v / l : Vec3<T>{};
}
template <typename T>
constexpr Vec3<T> Min(const Vec3<T>& a, const Vec3<T>& b) {
    return {a.x < b.x ? a.x : b.x, a.y < b.y ? a.y : b.y, a.z < b.z ? a.z : b.z};
}
template <typename T>
constexpr Vec3<T> Max(const Vec3<T>& a, const Vec3<T>& b) {
    return {a.x > b.x ? a.x : b.x, a.y > b.y ? a.y : b.y, a.z > b.z ? a.z : b.z};
}

}  // namespace mebake

template <typename T>
struct fmt::formatter<mebake::Vec3<T>> : fmt::formatter<double> {
    template <typename Ctx>
    auto format(const mebake::Vec3<T>& v, Ctx& ctx) const {
        return fmt::format_to(ctx.out(), "({}, {}, {})", v.x, v.y, v.z);
    }
};
template <typename T>
struct fmt::formatter<mebake::Vec2<T>> : fmt::formatter<double> {
    template <typename Ctx>
    auto format(const mebake::Vec2<T>& v, Ctx& ctx) const {
        return fmt::format_to(ctx.out(), "({}, {})", v.x, v.y);
    }
};
