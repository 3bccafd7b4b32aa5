#include <solo/pipeline/large_buffer_allocator.h>

#include <climits>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace solo {

bool keepFreedLargeBuffersForReuse() {
#if defined(__GLIBC__)
  // mallopt returns 1 on success. M_MMAP_MAX = 0 serves every block from the heap (the main
  // arena grows with brk; a thread's arena that cannot fit a block retries in the main one).
  const bool no_mmap = mallopt(M_MMAP_MAX, 0) == 1;
  const bool no_trim = mallopt(M_TRIM_THRESHOLD, INT_MAX) == 1;
  return no_mmap && no_trim;
#else
  return false;
#endif
}

}  // namespace solo
