#pragma once
// Reading and writing a packing directory (docs/packing-format.md):
//   meta.json       format version, program version, N, Lx, Ly (L for a square cell), P_ext,
//                   mu, seed, F0, settings, command, run state, checksums of the two tables;
//   particles.csv   id,x,y,radius,vx,vy,omega
//   contacts.csv    a,b,nx,ny,lx,ly,gap,fn,ft
// Numbers are written with 17 significant digits, so a packing reloads bit for bit.
#include <filesystem>

#include "unjam/packing/packing.hpp"

namespace unjam {

inline constexpr int kPackingFormatVersion = 1;

// Reads and validates a packing; throws unjam::Error with a message naming the file, the
// line and the problem (missing file or column, truncated row, non-numeric or NaN value,
// index out of range, checksum mismatch).
Packing read_packing(const std::filesystem::path& dir);

// Writes the packing into `dir` (created if needed). Every file is written atomically and
// meta.json last, with checksums of the tables, so a reader detects an interrupted write.
void write_packing(const std::filesystem::path& dir, const Packing& packing);

}  // namespace unjam
