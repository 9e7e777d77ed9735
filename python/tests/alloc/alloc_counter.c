/* An allocation counter to preload into a Python process (LD_PRELOAD): it
 * forwards malloc, calloc, realloc, the aligned allocators and free to
 * glibc's own (__libc_*) and counts the calls made on the threads that asked
 * to be counted. The allocation proof for run_servo reads the counts with
 * ctypes (python/tests/test_alloc.py): a servo tick must make none.
 *
 * Counting is per thread, so a worker thread that allocates by design (the
 * video field's frame preparer) does not blur what the servo thread does.
 * The flag and counts live in initial-exec TLS: reading them never calls
 * into the dynamic loader, which could allocate. */
#include <errno.h>
#include <stddef.h>
#include <malloc.h>
#include <stdint.h>
#include <stdlib.h>

extern void* __libc_malloc(size_t size);
extern void* __libc_calloc(size_t n, size_t size);
extern void* __libc_realloc(void* p, size_t size);
extern void* __libc_memalign(size_t alignment, size_t size);
extern void __libc_free(void* p);

#define HF_TLS __thread __attribute__((tls_model("initial-exec")))

static HF_TLS int counted;                /* this thread is counted */
static HF_TLS unsigned long allocations;  /* malloc, calloc, realloc, aligned allocations */
static HF_TLS unsigned long frees;        /* free of a non-null pointer */

static inline void count_allocation(void) {
  if (counted) ++allocations;
}

/* ---- the interface read through ctypes ---- */

/* Starts (on != 0) or stops counting the calling thread; clears its counts. */
void hapticfield_count_here(int on) {
  counted = on != 0;
  allocations = 0;
  frees = 0;
}
/* Allocation calls made on the calling thread while it was counted. */
unsigned long hapticfield_malloc_calls(void) { return allocations; }
/* free() calls (of non-null pointers) made on the calling thread while counted. */
unsigned long hapticfield_free_calls(void) { return frees; }
/* Self-test: n malloc + free pairs through the interposed symbols (the
 * counter must see n of each). */
unsigned long hapticfield_alloc_self_test(int n) {
  void* volatile sink = 0;
  for (int i = 0; i < n; ++i) {
    void* (*volatile m)(size_t) = malloc;
    void (*volatile f)(void*) = free;
    sink = m(48);
    f(sink);
  }
  return (unsigned long)n;
}

/* ---- the interposed allocator ---- */

void* malloc(size_t size) {
  count_allocation();
  return __libc_malloc(size);
}

void* calloc(size_t n, size_t size) {
  count_allocation();
  return __libc_calloc(n, size);
}

void* realloc(void* p, size_t size) {
  count_allocation();
  return __libc_realloc(p, size);
}

void free(void* p) {
  if (p && counted) ++frees;
  __libc_free(p);
}

void* memalign(size_t alignment, size_t size) {
  count_allocation();
  return __libc_memalign(alignment, size);
}

void* aligned_alloc(size_t alignment, size_t size) {
  count_allocation();
  return __libc_memalign(alignment, size);
}

int posix_memalign(void** out, size_t alignment, size_t size) {
  if (alignment < sizeof(void*) || (alignment & (alignment - 1)) != 0) return EINVAL;
  count_allocation();
  void* p = __libc_memalign(alignment, size);
  if (!p && size) return ENOMEM;
  *out = p;
  return 0;
}
