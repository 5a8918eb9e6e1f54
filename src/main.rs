fn main() -> std::process::ExitCode {
    keep_freed_memory();
    // Before any thread starts: every thread must inherit the blocked signals.
    if let Err(e) = latticebuild::interrupt::install() {
        eprintln!("error: cannot take over Ctrl-C: {e}");
        return std::process::ExitCode::from(1);
    }
    latticebuild::cli::main()
}

/// Tells glibc's allocator to keep large freed blocks for reuse instead of handing them back
/// to the kernel. A tiling allocates and frees tens of MB per chunk (vertices, triangles,
/// weld tables), a thousand times for a big scaffold: by default each of those is a fresh
/// `mmap`, and every page of it faults in zeroed again — measured on a 100k-tet scaffold,
/// 0.7 s of system time of a 5.5 s build, gone with these settings (peak memory +80 MB).
/// Only blocks of 256 MiB and more are still mapped on their own.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn keep_freed_memory() {
    const MMAP_THRESHOLD: libc::c_int = 256 << 20;
    const TRIM_THRESHOLD: libc::c_int = 1 << 30;
    // SAFETY: `mallopt` only sets allocator parameters; it is called before any other thread
    // exists, and a refused setting (return value 0) just leaves glibc's default.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, MMAP_THRESHOLD);
        libc::mallopt(libc::M_TRIM_THRESHOLD, TRIM_THRESHOLD);
    }
}

#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
fn keep_freed_memory() {}
