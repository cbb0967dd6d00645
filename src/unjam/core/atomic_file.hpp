#pragma once
// Output files are written atomically: into a temporary file beside the target, flushed,
// then renamed over it, so an interrupted run never leaves a half-written file and an
// earlier version stays intact until the new one is complete.
#include <filesystem>
#include <string>
#include <string_view>

namespace unjam {

// Writes `content` to `path` atomically; throws unjam::Error on failure.
void write_file_atomic(const std::filesystem::path& path, std::string_view content);

// Throws unjam::Error (naming the place and the reason) unless a file can be written at `path`
// by write_file_atomic: creates its directory, creates and removes the temporary file beside
// it. For a run's single file written only after minutes of work (an output directory is
// checked by taking its core/dir_lock).
void require_writable(const std::filesystem::path& path);

// Renames `from` to `to` (replacing it atomically); throws unjam::Error on failure.
void rename_file(const std::filesystem::path& from, const std::filesystem::path& to);

// Flushes a directory's entries (the renames into it) to disk.
void sync_directory(const std::filesystem::path& dir);

// Removes the temporary files (NAME.tmp.PID) that processes no longer running left in
// `dir` when they were stopped during a write.
void remove_stale_temporaries(const std::filesystem::path& dir);

// FNV-1a, 64 bit, of the bytes of a file, as 16 hex digits: the checksums of a packing and
// of a probe checkpoint (docs/packing-format.md).
std::string fnv1a64_hex(std::string_view bytes);

// Reads a whole file; throws unjam::Error naming the file if it cannot be read.
std::string read_file(const std::filesystem::path& path);

}  // namespace unjam
