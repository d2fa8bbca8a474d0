//! How the C allocator treats freed memory while frames are drawn on a software GPU.
//!
//! Mesa's lavapipe frees and allocates again about 8 MB on one of its threads every frame. With
//! glibc's default trim threshold (128 KiB, raised to twice the largest block freed so far) that
//! thread's arena hands the memory back to the kernel (`madvise`) after every frame and faults
//! it back in, page by page, during the next: about 730 page faults a frame, and 4-5 ms of a
//! 40 ms frame of the modern look on the project's 2-core machine. [`keep_freed_memory`] lets
//! every arena keep up to [`KEPT_FREED_BYTES`] of freed memory instead (7 page faults a frame).

/// Freed memory an arena keeps at its top before returning it to the kernel, in bytes.
pub const KEPT_FREED_BYTES: usize = 64 << 20;

/// Asks glibc's allocator to keep up to [`KEPT_FREED_BYTES`] of freed memory in each arena. It
/// is a setting of the whole process, so call it once at the start of a program that draws
/// frames; freed blocks of more than glibc's mmap threshold are still returned at once. Does
/// nothing with other C libraries or systems.
pub fn keep_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        // SAFETY: `mallopt` changes one of glibc's tuning parameters under the allocator's own
        // locks, and M_TRIM_THRESHOLD accepts any non-negative value. It returns 0 on failure,
        // which leaves the default in place: nothing to report.
        #[allow(unsafe_code)]
        unsafe {
            libc::mallopt(libc::M_TRIM_THRESHOLD, KEPT_FREED_BYTES as libc::c_int);
        }
    }
}
