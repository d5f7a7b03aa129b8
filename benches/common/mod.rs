//! Shared by the benchmarks.
// Each benchmark uses only part of this module.
#![allow(dead_code)]

/// The median of a few timings (the upper middle one for an even count).
pub fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// CPU seconds (user + system, all threads) this process and its finished children have used,
/// to the microsecond (`/proc`'s ticks are 10 ms, too coarse for reads of a few tens of ms).
pub fn cpu_seconds() -> f64 {
    let seconds = |who: libc::c_int| {
        // SAFETY: `rusage` is plain data that getrusage fills in; all zeros is a valid value.
        let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
        // SAFETY: a valid `who` and a pointer to a live, writable rusage.
        if unsafe { libc::getrusage(who, &mut usage) } != 0 {
            return 0.0;
        }
        let time = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
        time(usage.ru_utime) + time(usage.ru_stime)
    };
    seconds(libc::RUSAGE_SELF) + seconds(libc::RUSAGE_CHILDREN)
}

/// The 1-, 5- and 15-minute load averages: CPU figures are comparable only at similar load.
pub fn load() -> String {
    let text = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    text.split_whitespace().take(3).collect::<Vec<_>>().join(" ")
}
