#pragma once
// Units of the model (docs/method.md, "Model and units"). Length: the largest radius R_max = 1.
// Areal mass density rho = 1. Pressure: P_ext (default 1).
#include <numbers>

namespace unjam {

inline constexpr double kPi = std::numbers::pi;

// Area of a disk of radius R: pi R^2.
inline double disk_area(double R) { return kPi * R * R; }

// Mass of a disk of radius R at areal density 1: m = pi R^2.
inline double disk_mass(double R) { return disk_area(R); }

// Moment of inertia of a uniform disk: I = m R^2 / 2.
inline double disk_inertia(double R) { return 0.5 * disk_mass(R) * R * R; }

// Force unit of the paper: F0 = 2 R_avg P_ext.
inline double force_unit(double R_avg, double P_ext) { return 2.0 * R_avg * P_ext; }

}  // namespace unjam
