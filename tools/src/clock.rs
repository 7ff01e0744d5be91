//! Clocks and machine state for benchmarks: thread and process CPU time, the load other
//! processes put on the machine, and the x86 flush-to-zero / denormals-are-zero switches.
//!
//! The clocks follow the Embree harness (`../shared/bench/embree_bench.c`), so figures printed by
//! a Rust tool compare with its `BUILD`/`TRACE` lines.

use std::time::Instant;

/// Returns the value of a POSIX clock in seconds (0 if the clock cannot be read).
fn posix_clock_s(id: libc::clockid_t) -> f64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable timespec for the duration of the call.
    let rc = unsafe { libc::clock_gettime(id, &mut ts) };
    if rc != 0 {
        return 0.0;
    }
    ts.tv_sec as f64 + 1e-9 * ts.tv_nsec as f64
}

/// Returns the CPU time of the calling thread in seconds (`CLOCK_THREAD_CPUTIME_ID`).
pub fn thread_cpu_s() -> f64 {
    posix_clock_s(libc::CLOCK_THREAD_CPUTIME_ID)
}

/// Returns the CPU time of the whole process, all threads, in seconds.
pub fn process_cpu_s() -> f64 {
    posix_clock_s(libc::CLOCK_PROCESS_CPUTIME_ID)
}

/// Returns this process's user + system time from `getrusage`, in seconds.
fn self_busy_s() -> f64 {
    // SAFETY: an all-zero rusage is a valid value; getrusage only writes into it.
    let mut ru: libc::rusage = unsafe { std::mem::zeroed() };
    // SAFETY: `ru` is a valid, writable rusage.
    if unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut ru) } != 0 {
        return 0.0;
    }
    let tv = |t: libc::timeval| t.tv_sec as f64 + 1e-6 * t.tv_usec as f64;
    tv(ru.ru_utime) + tv(ru.ru_stime)
}

/// Returns the machine's busy CPU seconds from `/proc/stat` (0 where it cannot be read).
fn machine_busy_s() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/stat") else {
        return 0.0;
    };
    let Some(line) = stat.lines().next() else {
        return 0.0;
    };
    let v: Vec<f64> = line
        .split_whitespace()
        .skip(1)
        .filter_map(|s| s.parse().ok())
        .collect();
    if v.len() < 8 {
        return 0.0;
    }
    // user nice system [idle iowait] irq softirq steal, as embree_bench counts them.
    // SAFETY: sysconf has no memory-safety preconditions.
    let hz = unsafe { libc::sysconf(libc::_SC_CLK_TCK) }.max(1) as f64;
    (v[0] + v[1] + v[2] + v[5] + v[6] + v[7]) / hz
}

/// A snapshot for measuring the CPU that *other* processes use over an interval.
#[derive(Clone, Copy, Debug)]
pub struct LoadProbe {
    wall: Instant,
    busy: f64,
    own: f64,
}

impl LoadProbe {
    /// Returns a snapshot of the wall clock, the machine's busy time and this process's time.
    pub fn now() -> LoadProbe {
        LoadProbe {
            wall: Instant::now(),
            busy: machine_busy_s(),
            own: self_busy_s(),
        }
    }

    /// Returns the cores other processes kept busy between `self` and `later` (0 for < 50 ms).
    pub fn other_load(&self, later: &LoadProbe) -> f64 {
        let dt = later.wall.duration_since(self.wall).as_secs_f64();
        if dt <= 0.05 {
            return 0.0;
        }
        (((later.busy - self.busy) - (later.own - self.own)) / dt).max(0.0)
    }
}

/// Switches on flush-to-zero and denormals-are-zero for the calling thread; returns whether it
/// could (false on targets without SSE's MXCSR).
pub fn enable_ftz_daz() -> bool {
    #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
    {
        const FTZ: u32 = 1 << 15;
        const DAZ: u32 = 1 << 6;
        let mut csr: u32 = 0;
        // SAFETY: stmxcsr/ldmxcsr read and write this thread's MXCSR only; every SSE2 target has
        // it, and setting FTZ/DAZ changes only how denormals round, never memory safety.
        unsafe {
            std::arch::asm!("stmxcsr [{}]", in(reg) &mut csr, options(nostack));
            csr |= FTZ | DAZ;
            std::arch::asm!("ldmxcsr [{}]", in(reg) &csr, options(nostack, readonly));
        }
        true
    }
    #[cfg(not(any(target_arch = "x86", target_arch = "x86_64")))]
    {
        false
    }
}

/// Returns the median of `xs` (0 for an empty slice).
pub fn median(xs: &[f64]) -> f64 {
    let mut v = xs.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    match n {
        0 => 0.0,
        _ if n % 2 == 1 => v[n / 2],
        _ => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// Returns the smallest of `xs` (infinity for an empty slice).
pub fn min(xs: &[f64]) -> f64 {
    xs.iter().copied().fold(f64::INFINITY, f64::min)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ftz_flushes_denormal_results() {
        let handle = std::thread::spawn(|| {
            let tiny = std::hint::black_box(f32::MIN_POSITIVE);
            let before = tiny * std::hint::black_box(0.5f32);
            let on = enable_ftz_daz();
            let after = tiny * std::hint::black_box(0.5f32);
            (before, on, after)
        });
        let (before, on, after) = handle.join().unwrap();
        assert!(before > 0.0);
        if on {
            assert_eq!(after, 0.0);
        }
    }

    #[test]
    fn clocks_advance_and_median_is_the_middle() {
        let c0 = thread_cpu_s();
        let mut x = 0u64;
        for i in 0..2_000_000u64 {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(i);
        }
        std::hint::black_box(x);
        assert!(thread_cpu_s() > c0 && process_cpu_s() > 0.0);
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), 2.5);
        assert_eq!(min(&[4.0, 1.0]), 1.0);
    }
}
