#pragma once
// Process-wide heap policy for the CLI (and benchmarks that time what it runs).
namespace lb {

/// Keep freed large blocks in the heap for reuse instead of returning them to the kernel
/// (glibc mallopt: mmap threshold 1 GiB, trim threshold 2 GiB). Training and rollouts
/// allocate batch-sized matrices (tens of MB on the full-size scenes) every batch; with
/// glibc's defaults the heap top is trimmed after each batch and its pages fault in and are
/// zeroed again on the next (18 brk calls per full-cloth epoch). Until 2026-12-03 this
/// function compiled to nothing (allocator.cpp tested __GLIBC__ before including a C
/// library header), so the figures once quoted here (bunny_ears 588 → 495 ms) came from
/// the other changes of that commit. Measured with the policy in effect, 2026-12-03, this
/// AMD EPYC, 2 threads: train_epoch/cloth_float32 43.5 → 31.1 ms, cloth 53.9 → 51.0 ms.
/// The peak heap stays reserved. No effect where the C library is not glibc.
void keep_freed_memory();

} // namespace lb
