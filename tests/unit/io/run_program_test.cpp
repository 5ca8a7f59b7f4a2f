// runProgram: the exit codes of every program, and the allocator setting that keeps Cyclone's
// receive buffers out of the heap (keepLargeBlocksMapped).

#include <gtest/gtest.h>
#include <malloc.h>

#include <cstdlib>
#include <stdexcept>

#include "sensornet/core/input_error.hpp"
#include "sensornet/io/command_line.hpp"
#include "support/sanitizer.hpp"

namespace sensornet {
namespace {

constexpr std::size_t kReceiveBufferBytes = 1024 * 1024;  // Cyclone's receive buffer

// Blocks glibc has mapped by themselves right now.
std::size_t mappedBlocks() { return ::mallinfo2().hblks; }

// A receive buffer's life: allocated, written (so the compiler keeps it), freed. Returns how many
// more blocks were mapped while it lived.
std::size_t mappedWhileAlive() {
  const std::size_t before = mappedBlocks();
  char* volatile block = static_cast<char*>(std::malloc(kReceiveBufferBytes));
  if (block == nullptr) return 0;
  block[0] = 1;
  block[kReceiveBufferBytes - 1] = 1;
  const std::size_t during = mappedBlocks();
  std::free(block);
  return during - before;
}

// With glibc's dynamic threshold, the first such block is mapped, and once it is freed the
// threshold rises past it, so the next one comes from the heap and its pages stay resident
// after it is freed. Inside runProgram every one of them is mapped (removing the mallopt call
// from keepLargeBlocksMapped makes the second and third counts 0).
TEST(RunProgram, ReceiveBufferSizedBlocksStayMappedAfterOneIsFreed) {
  if (sensornet::testing::kAddressSanitizer) GTEST_SKIP() << sensornet::testing::kNoGlibcHeap;
  std::size_t first = 0, second = 0, third = 0;
  const int code = runProgram("test", [&] {
    first = mappedWhileAlive();
    second = mappedWhileAlive();
    third = mappedWhileAlive();
    return kExitOk;
  });
  EXPECT_EQ(code, kExitOk);
  EXPECT_EQ(first, 1u);
  EXPECT_EQ(second, 1u);
  EXPECT_EQ(third, 1u);
}

TEST(RunProgram, MapsErrorsToTheDocumentedExitCodes) {
  EXPECT_EQ(runProgram("test", [] { return 7; }), 7);
  EXPECT_EQ(runProgram("test",
                       []() -> int { throw InputError("file.yaml", "field", "a number"); }),
            kExitBadInput);
  EXPECT_EQ(runProgram("test", []() -> int { throw std::runtime_error("broken"); }),
            kExitFailure);
}

}  // namespace
}  // namespace sensornet
