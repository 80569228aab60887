#include "solve/sky.h"

#include "solve/basis.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace mebake::solve {
namespace {

// Brute-force integrals over the sphere: theta split in 16 panels x 8 Gauss points, phi in
// 32 panels x 8; the kinks (horizon of n) are resolved by the panel count, tolerance follows.
struct Brute {
    Vec3d e;
    double irradiance = 0;
};
Brute Integrate(const SkyModel& sky, const Vec3d& n) {
    const GaussRule& g = Gauss(8);
    const Vec3d w = sky.up;
    const Vec3d t = std::abs(w.x) < 0.9 ? Vec3d{1, 0, 0} : Vec3d{0, 1, 0};
    const Vec3d u = Normalize(Cross(t, w)), v = Cross(w, u);
    Brute b;
    const int pt = 64, pp = 128;
    for (int i = 0; i < pt; ++i) {
        for (int a = 0; a < 8; ++a) {
            const double theta = (i + g.x[a]) / pt * (M_PI / 2);
            const double wt = g.w[a] / pt * (M_PI / 2);
            for (int j = 0; j < pp; ++j) {
                for (int c = 0; c < 8; ++c) {
                    const double phi = (j + g.x[c]) / pp * 2 * M_PI;
                    const double wp = g.w[c] / pp * 2 * M_PI;
                    const Vec3d d = u * (std::sin(theta) * std::cos(phi)) +
                                    v * (std::sin(theta) * std::sin(phi)) + w * std::cos(theta);
                    const double dw = std::sin(theta) * wt * wp;
                    const double l = sky.Radiance(d);
                    b.e += d * (l * dw);
                    b.irradiance += l * std::max(0.0, Dot(n, d)) * dw;
                }
            }
        }
    }
    return b;
}

TEST(Sky, VectorIrradianceClosedForms) {
    const Vec3d up = Normalize(Vec3d{0.2, -0.1, 1});
    const Vec3d eu = SkyVectorIrradiance(SkyModel::Uniform(2.0, up));
    EXPECT_NEAR(Length(eu - up * (M_PI * 2.0)), 0.0, 1e-12);
    const Vec3d ec = SkyVectorIrradiance(SkyModel::CieOvercast(3.0, up));
    EXPECT_NEAR(Length(ec - up * (7 * M_PI / 9 * 3.0)), 0.0, 1e-12);
    // CIE overcast: zenith 3x brighter than the horizon.
    const SkyModel cie = SkyModel::CieOvercast(3.0, up);
    EXPECT_NEAR(cie.Radiance(up), 3.0, 1e-12);
    EXPECT_NEAR(cie.Radiance(Normalize(Cross(up, Vec3d{1, 0, 0}))), 1.0, 1e-12);
    EXPECT_EQ(cie.Radiance(-up), 0.0);
}

TEST(Sky, TiltedIrradianceMatchesBruteForce) {
    std::mt19937 rng(1);
    std::normal_distribution<double> nd;
    const Vec3d up{0, 0, 1};
    for (const SkyModel& sky : {SkyModel::Uniform(1.5, up), SkyModel::CieOvercast(2.0, up)}) {
        const Brute flat = Integrate(sky, up);
        EXPECT_NEAR(Length(flat.e - SkyVectorIrradiance(sky)), 0.0, 1e-9);
        std::vector<Vec3d> normals = {up, -up, {1, 0, 0}, Normalize(Vec3d{1, 1, 1})};
        for (int i = 0; i < 6; ++i)
            normals.push_back(Normalize(Vec3d{nd(rng), nd(rng), nd(rng)}));
        for (const Vec3d& n : normals) {
            const double ref = Integrate(sky, n).irradiance;
            EXPECT_NEAR(SkyIrradiance(sky, n), ref, 2e-5 * (1 + ref))
                << n.x << "," << n.y << "," << n.z;
        }
    }
    // Uniform sky on a vertical wall: pi L (1 + cos 90deg) / 2.
    EXPECT_NEAR(SkyIrradiance(SkyModel::Uniform(1, up), {1, 0, 0}), M_PI / 2, 1e-12);
    EXPECT_NEAR(SkyIrradiance(SkyModel::CieOvercast(1, up), up), 7 * M_PI / 9, 1e-12);
    EXPECT_EQ(SkyIrradiance(SkyModel::CieOvercast(1, up), -up), 0.0);
}

TEST(Sky, FibonacciSamplesConvergeToTheClosedForm) {
    const Vec3d up = Normalize(Vec3d{0.3, 0.4, 1});
    const SkyModel sky = SkyModel::CieOvercast(1.0, up);
    double prev = 1e9;
    for (int n : {64, 512, 4096}) {
        const SkySamples s = MakeSkySamples(sky, n);
        ASSERT_EQ(s.dir.size(), size_t(n));
        for (const Vec3f& d : s.dir) {
            EXPECT_NEAR(Length(d), 1.0f, 1e-6f);
            EXPECT_GT(Dot(Vec3d(d), up), 0.0);
        }
        const double err = Length(SkyTransfer(s, {}) - SkyVectorIrradiance(sky));
        EXPECT_LT(err, prev);
        prev = err;
    }
    EXPECT_LT(prev / Length(SkyVectorIrradiance(sky)), 1e-3);
    // Deterministic.
    EXPECT_EQ(MakeSkySamples(sky, 100).dir[37], MakeSkySamples(sky, 100).dir[37]);
}

TEST(Sky, OpennessAndBentNormal) {
    const Vec3d up{0, 0, 1};
    const SkyModel sky = SkyModel::Uniform(1.0, up);
    const SkySamples s = MakeSkySamples(sky, 2048);
    SkyVisibility all = SkyOpenness(s, {});
    EXPECT_NEAR(all.open_fraction, 1.0, 1e-12);
    EXPECT_NEAR(all.bent.z, 1.0, 1e-3);
    // A wall blocks every direction with x < 0: half the sky, bent towards +x.
    std::vector<uint8_t> vis(s.dir.size());
    for (size_t k = 0; k < vis.size(); ++k)
        vis[k] = s.dir[k].x > 0;
    SkyVisibility half = SkyOpenness(s, vis);
    EXPECT_NEAR(half.open_fraction, 0.5, 0.01);
    // Quarter sphere {z > 0, x > 0}: E = (pi/2, 0, pi/2) L, bent normal (1, 0, 1)/sqrt 2.
    EXPECT_NEAR(half.bent.x, std::sqrt(0.5), 5e-3);
    EXPECT_NEAR(half.bent.z, std::sqrt(0.5), 5e-3);
    const Vec3d e = SkyTransfer(s, vis);
    EXPECT_NEAR(e.z, M_PI / 2, 5e-3);  // half of pi L up
    EXPECT_NEAR(e.x, M_PI / 2, 5e-3);  // integral of sin^2 cos(phi) over the quarter
    std::vector<uint8_t> none(s.dir.size(), 0);
    EXPECT_EQ(SkyOpenness(s, none).open_fraction, 0.0);
    EXPECT_EQ(Length(SkyOpenness(s, none).bent), 0.0);
}

}  // namespace
}  // namespace mebake::solve
