#pragma once
/// @file ByteSize.h
/// Sizes as users write them on command lines ("512M", "2GiB", "64k", "1000000").

#include <cstdint>
#include <string>
#include <string_view>

namespace tetrapage {

/// Parses a byte count: a number (decimals allowed) with an optional suffix k, M, G, T
/// (powers of 1024; "KiB", "MB", "GiB" ... are read the same way) or B.
/// @throw InputError naming the text when it is not a size, is negative or overflows.
std::uint64_t parse_byte_size(std::string_view text);

/// "1.5 GiB", "640 KiB", "12 B".
std::string format_byte_size(std::uint64_t bytes);

}  // namespace tetrapage
