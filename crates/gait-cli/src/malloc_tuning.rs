//! glibc's allocator serves each decoded frame (5 MB on the sample, 25 MB at 4K) with a fresh
//! memory mapping and returns it to the system when the frame is dropped, so every frame of
//! every pass costs page faults and zeroed pages in the kernel: 1 CPU s of system time on the
//! sample's 9 s run. Kept in the heap instead, the buffers are reused (BENCHMARKS.md: system
//! time 3.2 -> 2.1 s, peak RSS +7-16 MiB).

/// Large blocks from the heap, and freed memory kept for reuse up to 256 MiB.
pub fn keep_frame_buffers() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets allocator parameters; called once, before any thread starts.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 64 << 20);
        libc::mallopt(libc::M_TRIM_THRESHOLD, 256 << 20);
    }
}
