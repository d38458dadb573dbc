// Sizes as users write them (ByteSize.h): the suffixes are binary whatever their spelling, and
// the text the command line shows for a size reads back as that size.

#include <gtest/gtest.h>

#include "tetrapage/formats/base/ByteSize.h"
#include "tetrapage/formats/base/Error.h"

namespace tetrapage {
namespace {

TEST(ByteSize, SuffixesArePowersOf1024HoweverSpelt) {
  EXPECT_EQ(parse_byte_size("1000"), 1000u);
  EXPECT_EQ(parse_byte_size("12B"), 12u);
  for (const char* text : {"64k", "64K", "64KB", "64KiB", "64kib"})
    EXPECT_EQ(parse_byte_size(text), 64u << 10) << text;
  for (const char* text : {"3M", "3m", "3MB", "3MiB"})
    EXPECT_EQ(parse_byte_size(text), 3u << 20) << text;
  for (const char* text : {"2G", "2GB", "2GiB"})
    EXPECT_EQ(parse_byte_size(text), std::uint64_t(2) << 30) << text;
  EXPECT_EQ(parse_byte_size("1T"), std::uint64_t(1) << 40);
  EXPECT_EQ(parse_byte_size("1.5G"), std::uint64_t(3) << 29);
  EXPECT_EQ(parse_byte_size("0.5k"), 512u);
}

TEST(ByteSize, RefusesWhatIsNotASize) {
  for (const char* text : {"", "G", "-1M", "12Q", "1 G", "1MBB", "nan", "inf", "1e30T"})
    EXPECT_THROW(parse_byte_size(text), InputError) << "'" << text << "'";
}

TEST(ByteSize, TextReadsBackExactly) {
  EXPECT_EQ(byte_size_text(0), "0");
  EXPECT_EQ(byte_size_text(1000), "1000");
  EXPECT_EQ(byte_size_text(1024), "1k");
  EXPECT_EQ(byte_size_text(1536 << 10), "1536k");
  EXPECT_EQ(byte_size_text(256 << 20), "256M");
  EXPECT_EQ(byte_size_text(std::uint64_t(1) << 30), "1G");
  EXPECT_EQ(byte_size_text(std::uint64_t(3) << 40), "3T");
  EXPECT_EQ(byte_size_text(std::uint64_t(1) << 50), "1024T");
  for (const std::uint64_t bytes :
       {std::uint64_t(1), std::uint64_t(1023), std::uint64_t(4096), std::uint64_t(5) << 33,
        (std::uint64_t(7) << 40) + 1, kDefaultMemoryBudget})
    EXPECT_EQ(parse_byte_size(byte_size_text(bytes)), bytes) << byte_size_text(bytes);
}

}  // namespace
}  // namespace tetrapage
