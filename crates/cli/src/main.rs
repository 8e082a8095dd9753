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

    /// glibc's heaps ("arenas"). By default each thread that allocates while another holds
    /// the heap gets one of its own (up to 8 per core), and a block freed into one is reused only
    /// by allocations served from it: the rayon workers' assembly blocks and the solve's
    /// vectors (a million-face map's are 8 MB, just below [`MMAP_THRESHOLD`]) each leave room
    /// behind in their thread's heap, how much depending on which thread ran what, which the
    /// machine's load decides. One heap for all threads reuses every freed block: the peak of a
    /// million-face isometric map fell from 920,284–920,752 KiB to 892,924–895,128 KiB (toe and
    /// hemisphere, alternately, load 13–17), its CPU time within the noise (the threads
    /// allocate whole blocks, not per element).
    const ARENA_MAX: i32 = 1;

    /// Fixes glibc's mapping threshold at [`MMAP_THRESHOLD`] (which also stops its dynamic raise)
    /// and its number of heaps at [`ARENA_MAX`].
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    #[allow(unsafe_code)]
    pub fn return_large_blocks() {
        // SAFETY: `mallopt` only sets a parameter of the allocator; it is called here before
        // the program starts any thread, and glibc serialises it with allocations anyway. A
        // refusal (return 0) leaves glibc's default, which is correct, only larger.
        unsafe {
            libc::mallopt(libc::M_MMAP_THRESHOLD, MMAP_THRESHOLD);
            libc::mallopt(libc::M_ARENA_MAX, ARENA_MAX);
        }
    }

    /// Other allocators keep their own policy.
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    pub fn return_large_blocks() {}
}
