#pragma once
/// \file input_file.h
/// Reading a user's input files safely: only regular files of bounded size are read (a FIFO, a
/// device such as /dev/zero, a socket or a folder is refused before any byte is read), and JSON is
/// checked for size and nesting depth before it is parsed. The limits are listed in
/// docs/robustness.md; every refusal is an InputError naming the file.

#include <cstdint>
#include <string>

namespace pandora {

/// Limits on what Pandora reads. Each is far above what a real file of that kind needs.
struct InputLimits {
  /// Scene, suggestion and other JSON files (a scene with 10,000 cameras is about 3 MB).
  static constexpr std::uint64_t kJsonBytes = 64ull << 20;
  /// Nesting depth of JSON arrays and objects (a scene file needs 6).
  static constexpr int kJsonDepth = 64;
  /// Mesh files read through assimp.
  static constexpr std::uint64_t kMeshBytes = 2ull << 30;
  /// Texture images.
  static constexpr std::uint64_t kImageBytes = 512ull << 20;
};

/// Checks that `path` names a regular file (symbolic links followed) of at most `max_bytes` bytes
/// and returns its size. `what` names the file in messages ("scene file", "mesh file").
/// Throws InputError(path, "", ...) when it is missing, unreadable, a folder, a FIFO, a device, a
/// socket, or larger than `max_bytes`.
std::uint64_t CheckInputFile(const std::string& path, std::uint64_t max_bytes,
                             const std::string& what);

/// Reads the whole of `path` after the checks of CheckInputFile. The file is opened without
/// blocking and checked again through the open descriptor, so a path swapped for a FIFO between
/// the check and the read cannot block. Throws InputError as CheckInputFile, or when reading fails.
std::string ReadInputFile(const std::string& path, std::uint64_t max_bytes,
                          const std::string& what);

/// Checks JSON text before it is parsed: at most InputLimits::kJsonBytes bytes and at most
/// InputLimits::kJsonDepth nested arrays and objects (counted outside strings, in one pass), so a
/// hostile file cannot make the parser take minutes or gigabytes. Throws InputError(file, "$",
/// ...).
void CheckJsonLimits(const std::string& text, const std::string& file);

}  // namespace pandora
