#pragma once
/// @file FileChecks.h
/// Checks made before a file is opened or written: an input must be a regular file (opening a
/// FIFO blocks forever, a device or folder is no mesh), and an output must neither be one of
/// the inputs nor anything but a regular file (writing renames a temporary over it: a device
/// node or an input would be destroyed). Inputs count with every file reading them opens:
/// the parts and sub-assemblies of a manifest, the buffers of a glTF.

#include <filesystem>
#include <span>
#include <vector>

namespace tetrapage {

/// @throw IoError naming `path` when it exists and is not a regular file (after links).
void require_regular_file(const std::filesystem::path& path);

/// Every file that reading `input` opens: `input` itself; for a manifest (.json), each of its
/// sub-manifests and of the mesh files they name; for a glTF (.gltf, .glb), and for one named
/// by a manifest, the files its buffer and image URIs name.
/// @throw as read_manifest, for a manifest that cannot be read.
std::vector<std::filesystem::path> files_read_from(const std::filesystem::path& input);

/// Refuses, before anything is written, an output that exists and is not a regular file, that
/// is the same file as an input or as any file reading an input opens (files_read_from; by
/// device and inode, so links and other spellings count) or as another output. Empty paths
/// (outputs not asked for) are skipped.
/// @throw InputError naming the output and what it would destroy; as files_read_from.
void check_outputs(std::span<const std::filesystem::path> outputs, std::span<const std::filesystem::path> inputs);

}  // namespace tetrapage
