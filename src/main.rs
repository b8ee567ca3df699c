//! The `nimbus` command line.

mod cli;

use std::process::ExitCode;

fn main() -> ExitCode {
    // Rust ignores SIGPIPE, so printing to a closed pipe (`nimbus parity ... | head`) made
    // println! panic; with the default action the process ends quietly, as `cat` does.
    #[cfg(unix)]
    // SAFETY: called before any other thread exists; SIG_DFL is a valid disposition.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    // glibc serves an allocation from the heap once its size falls under a threshold that it
    // raises to the size of every large block freed (up to 32 MiB). Whole-image methods free
    // per-sample arrays of a few MiB each, which then stayed resident in the heap as holes,
    // idle at the next phase's peak (pathgraph at 512x384: a process peak of 197-209 bytes per
    // vertex against 179-182 with the threshold fixed). Fixed at 1 MiB, every block that large
    // is mapped for itself and unmapped when freed; its pages are faulted in afresh, which
    // costs nothing measurable (render times equal within noise).
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: called before any other thread exists or anything is allocated by nimbus;
    // M_MMAP_THRESHOLD takes a size in bytes.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 1 << 20);
    }
    cli::run()
}
