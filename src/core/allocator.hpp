#pragma once
// Process-wide heap policy for the CLI (and benchmarks that time what it runs).
namespace lb {

/// Keep freed large blocks in the heap for reuse instead of returning them to the kernel
/// (glibc mallopt: mmap threshold 1 GiB, trim threshold 2 GiB). Training and rollouts
/// allocate batch-sized matrices (tens of MB on the full-size scenes) every batch; with
/// glibc's defaults each is a fresh mmap whose pages fault in and are zeroed again, which
/// cost 16–19 % of a full-size training epoch (train_epoch/bunny_ears 588 → 495 ms,
/// rods_translate 694 → 565 ms, one thread, 2026-12-02). The peak heap stays reserved.
/// No effect where the C library is not glibc.
void keep_freed_memory();

} // namespace lb
