#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

#include "unjam/analysis/contact_frame.hpp"

namespace unjam {
namespace {

// A quadrupole in the frame: u = ((x^2 - y^2) / r^3, 2 x y / r^3) (units of g).
Vec2 quadrupole(double x, double y) {
  const double r = std::hypot(x, y);
  return {(x * x - y * y) / (r * r * r), 2.0 * x * y / (r * r * r)};
}

TEST(ContactFrame, AxesAreNormalAndTangent) {
  // n = +y, t = (-n_y, n_x) = -x: a lab vector along +x has frame components (0, -1).
  const ContactFrame f{Vec2(1.0, 2.0), Vec2(0.0, 1.0), tangent(Vec2(0.0, 1.0))};
  EXPECT_EQ(f.rotate(Vec2(1.0, 0.0)), Vec2(0.0, -1.0));
  EXPECT_EQ(f.rotate(Vec2(0.0, 3.0)), Vec2(3.0, 0.0));
  // A position one unit beyond the origin along n has frame coordinates (1, 0).
  const Cell cell{10.0, 10.0};
  EXPECT_EQ(f.position(cell, Vec2(1.0, 3.0)), Vec2(1.0, 0.0));
}

// A contact at an arbitrary angle whose contact point lies outside the cell (across x = Lx):
// a quadrupole field generated in the lab frame comes back exactly in the contact frame.
TEST(ContactFrame, QuadrupoleAcrossPeriodicBoundaryIsExact) {
  const Cell cell{20.0, 15.0};
  const double theta = 0.6, R_a = 0.8, R_b = 0.7, overlap = 1e-9;
  const Vec2 n(std::cos(theta), std::sin(theta)), t = tangent(n);
  const Vec2 r_a(19.6, 0.3);
  const double l = R_a + R_b - overlap;

  Particles P;
  P.resize(2);
  P.radius = {R_a, R_b};
  const Vec2 r_b = cell.wrap(r_a + l * n);
  P.x = {r_a.x(), r_b.x()};
  P.y = {r_a.y(), r_b.y()};
  Contact c;
  c.a = 0;
  c.b = 1;
  c.n = n;
  c.l = l * n;

  const ContactFrame frame = contact_frame(P, c);
  const Vec2 r_c = r_a + R_a * n;
  EXPECT_EQ(frame.origin, r_c);
  EXPECT_GT(r_c.x(), cell.Lx);  // the contact point is across the boundary
  EXPECT_EQ(frame.n, n);
  EXPECT_EQ(frame.t, t);

  // Grains at known frame coordinates (|(X, Y)| < 7 < L/2: inside the minimum image), placed
  // in the lab frame (wrapped into the cell) with lab displacements g Q rotated back.
  const double g = 1e-9;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  std::vector<Vec2> X = {Vec2(-R_a, 0.0), Vec2(l - R_a, 0.0)};  // grains a and b
  while (X.size() < 500) {
    const Vec2 q(7.0 * uni(rng), 7.0 * uni(rng));
    if (q.norm() < 7.0 && q.norm() > 0.1) X.push_back(q);
  }
  std::vector<double> x, y;
  std::vector<Vec2> u_lab, U;
  for (const Vec2& q : X) {
    const Vec2 r = cell.wrap(r_c + q.x() * n + q.y() * t);
    const Vec2 u = g * quadrupole(q.x(), q.y());
    x.push_back(r.x());
    y.push_back(r.y());
    u_lab.push_back(u.x() * n + u.y() * t);
    U.push_back(u);
  }
  x[0] = P.x[0], y[0] = P.y[0];
  x[1] = P.x[1], y[1] = P.y[1];

  FrameField out;
  to_contact_frame(frame, cell, x, y, u_lab, out);
  ASSERT_EQ(out.size(), X.size());
  for (std::size_t i = 0; i < X.size(); ++i) {
    EXPECT_NEAR(out.x[i], X[i].x(), 1e-12) << i;
    EXPECT_NEAR(out.y[i], X[i].y(), 1e-12) << i;
    EXPECT_NEAR(out.ux[i] / g, U[i].x() / g, 1e-12) << i;
    EXPECT_NEAR(out.uy[i] / g, U[i].y() / g, 1e-12) << i;
  }
  // Grain a at (-R_a, 0), grain b at (|l| - R_a, 0): b on the +x side.
  EXPECT_NEAR(out.x[0], -R_a, 1e-12);
  EXPECT_NEAR(out.x[1], l - R_a, 1e-12);
}

TEST(ContactFrame, MismatchedLengthsThrow) {
  const ContactFrame f;
  const Cell cell{10.0, 10.0};
  const std::vector<double> two(2, 0.0);
  const std::vector<Vec2> three(3, Vec2::Zero());
  FrameField out;
  EXPECT_THROW(to_contact_frame(f, cell, two, two, three, out), std::invalid_argument);
}

}  // namespace
}  // namespace unjam
