//! The `flatcut` binary: everything lives in the library so tests can call it in-process.

fn main() -> std::process::ExitCode {
    allocator::return_large_blocks();
    flatcut_cli::main()
}

/// The process's allocator policy, set once before any allocation of size.
mod allocator {
    /// Blocks from which glibc's allocator maps each allocation on its own and unmaps it when
    /// freed. Left to itself, glibc raises this threshold to the size of the largest block freed
    /// so far (up to 32 MiB), so that after the first large free every temporary below 32 MiB
    /// comes from the heap, and the heap keeps the room when it is freed: a million-face map's
    /// assembly temporaries (tens of MB, freed before its factorisations) then stay resident
    /// under the factor and the Newton solve. Fixed at 8 MiB, the peak of a million-face
    /// isometric map falls from 990,032 to 935,832 KiB (toe, one run each, load 1.6–1.8; 4 MiB:
    /// 898,440 KiB for 0.6 s more system time in page faults), at 0.1 s of CPU time.
    const MMAP_THRESHOLD: i32 = 8 << 20;

    /// Fixes glibc's mapping threshold at [`MMAP_THRESHOLD`] (which also stops its dynamic raise).
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    #[allow(unsafe_code)]
    pub fn return_large_blocks() {
        // SAFETY: `mallopt` only sets a parameter of the allocator; it is called here before
        // the program starts any thread, and glibc serialises it with allocations anyway. A
        // refusal (return 0) leaves glibc's default, which is correct, only larger.
        unsafe {
            libc::mallopt(libc::M_MMAP_THRESHOLD, MMAP_THRESHOLD);
        }
    }

    /// Other allocators keep their own policy.
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    pub fn return_large_blocks() {}
}
