//! A refactoring safety net: with `CAUSTIC_FILM_LOG=FILE` set, every film the camera pass makes
//! appends one line to `FILE`: who rendered it, its size and a hash of its pixels and sample
//! counts. Run the test suite (and `tools/golden.sh`) before and after a change that must not
//! alter any image, then compare the sorted logs.
//!
//! Lines are keyed by the calling thread's name (the test's name under `cargo test`, `main` in
//! the CLI, which adds its command line) and a per-thread count, so the log does not depend on
//! the order tests run in. Off, it costs one environment lookup per frame.

use super::Film;
use std::cell::Cell;
use std::io::Write;

thread_local! {
    static COUNT: Cell<u32> = const { Cell::new(0) };
}

/// Returns the FNV-1a hash of a film's pixel bits and sample counts.
pub fn film_hash(film: &Film) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |v: u32| {
        for b in v.to_le_bytes() {
            h ^= b as u64;
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    };
    for p in &film.pixels {
        eat(p.x.to_bits());
        eat(p.y.to_bits());
        eat(p.z.to_bits());
    }
    for &s in &film.samples {
        eat(s);
    }
    h
}

/// Appends `film`'s line to the log named by `CAUSTIC_FILM_LOG`, when set.
pub fn record(film: &Film) {
    let Some(path) = std::env::var_os("CAUSTIC_FILM_LOG") else {
        return;
    };
    let n = COUNT.with(|c| {
        c.set(c.get() + 1);
        c.get()
    });
    let thread = std::thread::current();
    let mut who = thread.name().unwrap_or("?").to_string();
    if who == "main" {
        let args: Vec<String> = std::env::args().skip(1).collect();
        who = format!("main[{}]", args.join(" "));
    }
    let w = film.window;
    let line = format!(
        "{who}#{n} {}x{} at {},{} of {}x{} {:016x}\n",
        film.width,
        film.height,
        w.x0,
        w.y0,
        w.full_width,
        w.full_height,
        film_hash(film)
    );
    if let Ok(mut f) = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)
    {
        let _ = f.write_all(line.as_bytes());
    }
}
