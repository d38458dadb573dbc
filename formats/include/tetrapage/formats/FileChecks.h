#pragma once
/// @file FileChecks.h
/// Checks made before a file is opened or written: an input must be a regular file (opening a
/// FIFO blocks forever, a device or folder is no mesh), and an output must neither be one of
/// the inputs nor anything but a regular file (writing renames a temporary over it: a device
/// node or an input would be destroyed).

#include <filesystem>
#include <span>

namespace tetrapage {

/// @throw IoError naming `path` when it exists and is not a regular file (after links).
void require_regular_file(const std::filesystem::path& path);

/// Refuses, before anything is written, an output that exists and is not a regular file, that
/// is the same file as an input (by device and inode, so links and other spellings count) or
/// as another output. Empty paths (outputs not asked for) are skipped.
/// @throw InputError naming the output and what it would destroy.
void check_outputs(std::span<const std::filesystem::path> outputs, std::span<const std::filesystem::path> inputs);

}  // namespace tetrapage
