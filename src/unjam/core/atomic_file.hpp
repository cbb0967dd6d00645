#pragma once
// Output files are written atomically: into a temporary file beside the target, flushed,
// then renamed over it, so an interrupted run never leaves a half-written file and an
// earlier version stays intact until the new one is complete.
#include <filesystem>
#include <string_view>

namespace unjam {

// Writes `content` to `path` atomically; throws unjam::Error on failure.
void write_file_atomic(const std::filesystem::path& path, std::string_view content);

// Reads a whole file; throws unjam::Error naming the file if it cannot be read.
std::string read_file(const std::filesystem::path& path);

}  // namespace unjam
