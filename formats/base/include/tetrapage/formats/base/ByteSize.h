#pragma once
/// @file ByteSize.h
/// Sizes as users write them on command lines ("512M", "2GiB", "64k", "1000000").

#include <cstdint>
#include <string>
#include <string_view>

namespace tetrapage {

/// The memory budget of every library option and command that takes one, when none is given:
/// the runtime's decoded shards (CollisionIndexOptions, tetrapage_open's
/// TETRAPAGE_DEFAULT_BUDGET_BYTES, `fly`, `render`, `generate flight --index`) and the
/// preprocess's working data (PreprocessOptions, `preprocess`). 1 GiB: the runtime reserves and
/// fills at most the index's own shard bytes, so a larger budget costs a small index nothing,
/// while a large one keeps more of its shards resident; the preprocess holds the parts' soups
/// in memory up to a quarter of it (about 9M triangles) before it spills them to disk.
inline constexpr std::uint64_t kDefaultMemoryBudget = std::uint64_t(1) << 30;

/// Parses a byte count: a number (decimals allowed) with an optional suffix k, M, G, T
/// (powers of 1024; "KiB", "MB", "GiB" ... are read the same way) or B.
/// @throw InputError naming the text when it is not a size, is negative or overflows.
std::uint64_t parse_byte_size(std::string_view text);

/// "1.5 GiB", "640 KiB", "12 B".
std::string format_byte_size(std::uint64_t bytes);

/// The shortest text that parse_byte_size reads back as exactly `bytes`, in the largest unit
/// that divides it: "1G", "256M", "1536k", "1000".
std::string byte_size_text(std::uint64_t bytes);

}  // namespace tetrapage
