#pragma once
// A packing for visualisers (docs/packing-format.md, "Exports"):
//   VTK XML PolyData (.vtp, ParaView): grains as points with radius, velocity, omega and an
//     optional displacement field; contacts as lines with fn, ft and their state;
//   extended XYZ (.xyz, OVITO, ASE): the cell as the lattice, one line per grain with the same
//     per-grain fields (the format has no bonds: contacts stay in contacts.csv).
// Both are plain text, numbers in the shortest form that reloads bit for bit. The sign
// conventions are those of packing/contact.hpp.
#include <filesystem>
#include <string>
#include <vector>

#include "unjam/core/vec2.hpp"
#include "unjam/packing/packing.hpp"

namespace unjam {

// A per-grain displacement field exported with the packing, e.g. one probe's
// (docs/probe.md, "The probe"): u (length units), u / g and the rotation (radians) of every grain.
struct GrainDisplacement {
  std::vector<Vec2> u;
  std::vector<Vec2> u_over_g;
  std::vector<double> rot;
  int contact = -1;  // the probed contact, or -1 if unknown
};

// Reads a field written by `unjam probe --contact K` (probe-K.csv: id, ux, uy, rot, ux_g,
// uy_g). Throws unjam::Error if a column is missing or the ids are not 0 .. N-1 of the packing.
GrainDisplacement read_displacement_csv(const std::filesystem::path& path, std::size_t N);

// What an export records besides the data: the packing it came from and the command.
struct ExportRecord {
  std::string source;   // packing directory
  std::string command;  // command line (or Python call) that wrote the export
};

// The contact states exported: ContactState (packing/contact.hpp) with tol = kExportStateTol F0:
// 0 closed, 1 sliding, 2 open.
inline constexpr double kExportStateTol = 1e-9;

// VTK XML PolyData, ASCII. Points: the N grain centres (z = 0), then one periodic image of b
// for every contact whose branch vector l crosses the cell boundary (so that each contact
// line is drawn from r_a to r_a + l); point data id (the grain), image (0 or 1), radius,
// velocity (vx, vy, 0), omega and, with a field, displacement, displacement_over_g (3
// components, z = 0) and rotation. Lines: one per contact, in the order of packing.contacts,
// with cell data contact, a, b, fn, ft, fn_over_F0 and state. Field data: Lx, Ly, mu, P_ext,
// F0, seed, probed_contact, and the strings program_version, source and command.
std::string vtk_polydata(const Packing& packing, const GrainDisplacement* field,
                         const ExportRecord& record);

// Extended XYZ: line 1 N, line 2 Lattice="Lx 0 0 0 Ly 0 0 0 Lz" (Lz = 2 R_max of the
// packing) Properties=id:I:1:pos:R:3:radius:R:1:velo:R:3:omega:R:1[:disp:R:3:disp_g:R:3:rot:R:1]
// pbc="T T F" and the record (mu, P_ext, F0, seed, program version, source, command), then one
// line per grain.
std::string extended_xyz(const Packing& packing, const GrainDisplacement* field,
                         const ExportRecord& record);

}  // namespace unjam
