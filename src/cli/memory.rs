//! The process's memory as the operating system counts it.

/// A `kB` field of `/proc/self/status`, in bytes.
fn status_bytes(field: &str) -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with(field))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Peak resident set size of this process in bytes (Linux's `VmHWM`); `None` where
/// `/proc/self/status` does not say.
pub fn peak_rss_bytes() -> Option<u64> {
    status_bytes("VmHWM:")
}

/// Resident set size of this process now, in bytes (`VmRSS`).
pub fn rss_bytes() -> Option<u64> {
    status_bytes("VmRSS:")
}

#[cfg(test)]
mod tests {
    #[test]
    #[cfg(target_os = "linux")]
    fn peak_rss_grows_with_what_was_touched() {
        let before = super::peak_rss_bytes().expect("Linux reports VmHWM");
        let block = vec![1u8; 64 << 20];
        std::hint::black_box(&block);
        let after = super::peak_rss_bytes().unwrap();
        assert!(after >= before.max(64 << 20), "{before} -> {after}");
        // The current size read first, the peak after: other tests' threads allocate too. Linux
        // counts resident pages per CPU (per thread, in batches of 64 pages, before 6.2) and
        // sums them approximately when read, so the peak may trail the size by a few MiB when
        // tests run in parallel.
        let now = super::rss_bytes().unwrap();
        let peak = super::peak_rss_bytes().unwrap();
        assert!(now <= peak + (16 << 20), "{now} > {peak}");
    }
}
