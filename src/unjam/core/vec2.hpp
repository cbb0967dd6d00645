#pragma once
// Two-dimensional vectors: Eigen's fixed-size type, and the 2D cross product.
#include <Eigen/Core>

namespace unjam {

using Vec2 = Eigen::Vector2d;

// z-component of a x b.
inline double cross(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

// The tangent of a contact normal: t = (-n_y, n_x), n rotated by +90 degrees, so n x t = 1.
inline Vec2 tangent(const Vec2& n) { return {-n.y(), n.x()}; }

}  // namespace unjam
