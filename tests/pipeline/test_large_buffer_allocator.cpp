#include <solo/pipeline/large_buffer_allocator.h>

#include <gtest/gtest.h>

#include <malloc.h>

#include <cstdlib>

namespace {

constexpr std::size_t kBlockBytes = std::size_t{64} << 20;  // above glibc's largest mmap threshold (32 MiB)

// Bytes the allocator holds in mmapped blocks while a 64 MiB block is alive, and the bytes it
// keeps free (not returned to the kernel) once the block is freed.
struct BlockFootprint {
  std::size_t mmapped_while_alive = 0;
  std::size_t kept_free_after = 0;
};

[[maybe_unused]] BlockFootprint allocateAndFree() {
  void* block = std::malloc(kBlockBytes);
  if (block == nullptr) return {};
  BlockFootprint footprint;
  footprint.mmapped_while_alive = mallinfo2().hblkhd;
  std::free(block);
  footprint.kept_free_after = mallinfo2().fordblks;
  return footprint;
}

}  // namespace

// One test, in this order: the setting is process-wide and cannot be undone.
TEST(LargeBufferAllocator, AFreedLargeBlockStaysInTheHeapForReuse) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP_("AddressSanitizer replaces malloc; the glibc setting does not apply");
#else
  const BlockFootprint by_default = allocateAndFree();
  EXPECT_GE(by_default.mmapped_while_alive, kBlockBytes) << "glibc's default mmaps a 64 MiB block";
  EXPECT_LT(by_default.kept_free_after, kBlockBytes) << "and unmaps it on free";

  ASSERT_TRUE(solo::keepFreedLargeBuffersForReuse());
  const BlockFootprint kept = allocateAndFree();
  EXPECT_EQ(kept.mmapped_while_alive, 0U);
  EXPECT_GE(kept.kept_free_after, kBlockBytes);

  // The kept memory serves the next block without growing the heap.
  const std::size_t heap_before = mallinfo2().arena;
  void* again = std::malloc(kBlockBytes);
  ASSERT_NE(again, nullptr);
  EXPECT_EQ(mallinfo2().arena, heap_before);
  std::free(again);
#endif
}
