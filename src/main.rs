//! The `sweepmtf` command: parses arguments and dispatches to the library.

mod cli;
mod gui;

fn main() -> std::process::ExitCode {
    keep_freed_memory();
    cli::main()
}

/// Asks glibc's allocator to keep freed memory for reuse instead of giving
/// it back to the kernel: a measurement allocates and frees several
/// megabytes per stage (location's reduced images, the bins, the pictures'
/// buffers), and every page the kernel hands out fresh is a page fault with
/// zeroing, ≈ 0.4 ms per MB on the 2-core VM of the README's timings. Blocks
/// of 4 MB and more (the decoded frame, raw planes) stay separate mappings,
/// backed by huge pages (`photo::hugebuf`). On the 24 MP target shot: 7 250
/// → 6 700 page faults, 3 % of the run.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn keep_freed_memory() {
    // SAFETY: mallopt only sets allocator parameters; called before any
    // other thread exists.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 4 << 20);
        libc::mallopt(libc::M_TRIM_THRESHOLD, 256 << 20);
    }
}

#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
fn keep_freed_memory() {}
