#pragma once
// Reading and writing a packing directory (docs/packing-format.md):
//   meta.json       format version, program version, N, Lx, Ly (L for a square cell), P_ext,
//                   mu, seed, F0, settings, command, run state, checksums of the two tables;
//   particles.csv   id,x,y,radius,vx,vy,omega
//   contacts.csv    a,b,nx,ny,lx,ly,gap,fn,ft
// Numbers are written with 17 significant digits, so a packing reloads bit for bit.
#include <filesystem>
#include <string>

#include "unjam/packing/packing.hpp"

namespace unjam {

inline constexpr int kPackingFormatVersion = 1;

// Reads and validates a packing; throws unjam::Error with a message naming the file, the
// line and the problem (missing file or column, truncated row, non-numeric or NaN value,
// index out of range, checksum mismatch, grains that do not fit the cell, contact rows that
// do not fit the positions: packing/geometry_check.hpp).
Packing read_packing(const std::filesystem::path& dir);

// The same checks on the texts of meta.json, particles.csv and contacts.csv; `dir` only names
// the files in messages (nothing is read from disk).
Packing parse_packing(const std::string& meta_text, std::string particles_text, std::string contacts_text,
                      const std::filesystem::path& dir);

// Writes the packing into `dir` (created if needed), replacing the previous version as a
// whole: a write stopped at any point leaves one complete version on disk, the previous or
// the new one, which read_packing finds (docs/packing-format.md). Temporary files left by
// stopped processes are removed.
void write_packing(const std::filesystem::path& dir, const Packing& packing);

// A hash (16 hex digits) of the cell, the grains and the contacts as write_packing writes
// them: outputs computed from a packing record it to tell whether they belong to it.
std::string packing_fingerprint(const Packing& packing);

}  // namespace unjam
