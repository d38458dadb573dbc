// The block reader under every text and binary reader (formats/mesh/src/InputFile.h): lines and
// records that straddle block boundaries, lines longer than a block, line ends, truncation.

#include "InputFile.h"

#include "TestSupport.h"

namespace tetrapage::test {
namespace {

using detail::InputFile;

TEST(InputFile, LinesAcrossBlocksMatchASimpleSplit) {
  const auto folder = scratch_folder("input_lines");
  Random random(31);
  std::string text;
  std::vector<std::string> expected;
  for (int line = 0; line < 3000; ++line) {
    // Mostly short lines, some far longer than the 4096-byte block.
    const std::size_t length =
        random.below(20) == 0 ? 5000 + random.below(10000) : random.below(80);
    std::string content;
    for (std::size_t i = 0; i < length; ++i)
      content.push_back(static_cast<char>('a' + random.below(26)));
    expected.push_back(content);
    text += content + (random.below(5) == 0 ? "\r\n" : "\n");
  }
  text += "last line without end";
  expected.push_back("last line without end");
  const auto path = folder / "lines.txt";
  write_file(path, text);

  InputFile file(path, 4096);
  EXPECT_EQ(file.size(), text.size());
  std::string_view line;
  std::size_t count = 0;
  while (file.next_line(line)) {
    ASSERT_LT(count, expected.size());
    ASSERT_EQ(line, expected[count]) << "seed 31 line " << count + 1;
    ++count;
    EXPECT_EQ(file.line_number(), count);
  }
  EXPECT_EQ(count, expected.size());
  EXPECT_EQ(file.offset(), text.size());
}

TEST(InputFile, RecordsAcrossBlocksAndTruncation) {
  const auto folder = scratch_folder("input_records");
  std::string bytes;
  for (int i = 0; i < 100000; ++i) bytes.push_back(static_cast<char>(i * 7 + i / 256));
  const auto path = folder / "records.bin";
  write_file(path, bytes);
  InputFile file(path, 4096);
  EXPECT_EQ(file.peek(5), std::string_view(bytes).substr(0, 5));
  std::size_t offset = 0;
  // Record sizes that do not divide the block, one larger than the block.
  for (std::size_t size : {13u, 4095u, 4097u, 10000u, 50u, 7u}) {
    for (int repeat = 0; repeat < 3; ++repeat) {
      const auto record = file.take(size);
      ASSERT_EQ(record.size(), size);
      ASSERT_EQ(std::string_view(record.data(), record.size()),
                std::string_view(bytes).substr(offset, size));
      offset += size;
      EXPECT_EQ(file.offset(), offset);
    }
  }
  const std::size_t left = bytes.size() - offset;
  const auto tail = file.take(left + 10);  // asks for more than there is
  EXPECT_EQ(tail.size(), left);
  EXPECT_TRUE(file.take(1).empty());
}

TEST(InputFile, OpenErrorsAreIoErrors) {
  const auto folder = scratch_folder("input_errors");
  expect_error<IoError>([&] { InputFile file(folder / "none"); }, {"none", "No such file"});
  expect_error<IoError>([&] { InputFile file(folder); }, {folder.string(), "folder"});
}

}  // namespace
}  // namespace tetrapage::test
