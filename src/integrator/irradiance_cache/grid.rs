//! How a lookup finds the records that may serve a point: grids by record size.
//!
//! A record serves points within its reach `a · R` (the accuracy times its radius), and the
//! reaches of one cache span the whole clamp of `R`: 25 times on the final scene at 1024², from
//! the contact regions' few pixels to a tenth of the room. One grid with cells as wide as the
//! largest region listed 43 records a lookup to find 3 that served (the final scene at 512²),
//! each read from the 128-byte records at random: a tenth of the camera pass.
//!
//! So the records are split into levels by reach, each level a factor of two, and each level
//! has a grid of its own whose cells are as wide as its largest reach: a record's region then
//! meets at most three cells along each axis, and a lookup reads one cell per level, listing
//! the records whose regions' cubes meet that cell. On the final scene at 512² a lookup lists
//! 10.8 records (42.8 with one grid; 19.5 with cells twice the largest reach, each region in
//! at most eight). A level's cells are kept in a hash table (only cells some record meets), so
//! the fine levels' small cells cost nothing where no record is.
//!
//! Each record has a 32-byte [`Entry`] with what the weight needs (position, normal, `R`), and
//! a cell lists the entries' indices; the 128-byte record is read only when it serves. Copies
//! of the entries in each cell's list were a fifth faster to read (`lookup` 1.20–1.35% of the
//! samples against 1.46–1.58%, final scene at 512²) but took up to 27 × 32 bytes a record, four
//! times the records themselves; the indices take at most 27 × 4.
//!
//! A record lies in one level and a point in one cell of each, so no record is listed twice for
//! one lookup. The records of a cell are in the order they were made, and the levels from the
//! smallest reach: the weighted sum is the same for any thread count.

use super::Record;
use glam::Vec3A;

/// Most levels; the reaches of the last one may span more than a factor of two.
const MAX_LEVELS: usize = 16;
/// Bits of a cell's coordinate along each axis in its key.
const KEY_BITS: u32 = 21;
/// Cells along an axis beyond which a level's cells are widened: 2^21.
const MAX_COORD: f32 = (1u32 << KEY_BITS) as f32;

/// What a lookup tests of a record.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub(super) struct Entry {
    p: [f32; 3],
    r: f32,
    n: [f32; 3],
    /// The record's index in the cache's records.
    pub index: u32,
}

impl Entry {
    fn new(index: usize, r: &Record) -> Entry {
        Entry {
            p: r.p.to_array(),
            r: r.r,
            n: r.n.to_array(),
            index: index as u32,
        }
    }

    /// Returns this record's weight at `p` (unit geometric normal `n`) for accuracy `a`, or
    /// `None` where it does not serve ([`weight`]).
    #[inline(always)]
    pub fn weight(&self, p: Vec3A, n: Vec3A, a: f32) -> Option<f32> {
        weight(
            (Vec3A::from_array(self.p), Vec3A::from_array(self.n), self.r),
            p,
            n,
            a,
        )
    }
}

/// Returns the weight `1 − ε/a` of a record at `rp` with normal `rn` and radius `rr` at `p`
/// (unit geometric normal `n`), or `None` where it does not serve: facing away, in front of the
/// point, or `ε ≥ a` (the cache's module doc).
#[inline(always)]
pub(super) fn weight((rp, rn, rr): (Vec3A, Vec3A, f32), p: Vec3A, n: Vec3A, a: f32) -> Option<f32> {
    let d = p - rp;
    let cos = n.dot(rn);
    if cos <= 0.0 || d.dot(n + rn) * 0.5 < -0.1 * a * rr {
        return None;
    }
    let eps = d.length() / rr + (1.0 - cos).max(0.0).sqrt();
    let w = 1.0 - eps / a;
    (w > 0.0).then_some(w)
}

/// A cell's list in [`Grid::lists`]; `key` is [`EMPTY`] for a free slot of the table.
#[derive(Clone, Copy, Debug)]
struct Slot {
    key: u64,
    start: u32,
    end: u32,
}

const EMPTY: u64 = u64::MAX;

/// The cells of one level, in an open-addressing table of [`Slot`]s.
#[derive(Clone, Debug)]
struct Level {
    inv_cell: f32,
    slots: Vec<Slot>,
    /// `64 − log2(slots.len())`: a key's hash is its product with a constant, shifted down.
    shift: u32,
}

/// The records' cells, level by level (the module doc).
#[derive(Clone, Debug, Default)]
pub(super) struct Grid {
    origin: Vec3A,
    levels: Vec<Level>,
    /// What a lookup tests of each record, in the records' order.
    entries: Vec<Entry>,
    /// The cells' lists of records, cell after cell.
    lists: Vec<u32>,
}

/// Returns the slot a key's probe starts at.
#[inline(always)]
fn home(key: u64, shift: u32) -> usize {
    (key.wrapping_mul(0x9e37_79b9_7f4a_7c15) >> shift) as usize
}

impl Grid {
    /// Returns the grid of `records` served with accuracy `accuracy` (`> 0`). A record whose
    /// position or reach is not finite, or whose reach is not positive, is not listed: the
    /// cache's own records have `R` clamped to `[R_min, R_max]` (a record of `R` 0 would serve
    /// nowhere, and one of infinite `R` everywhere).
    pub fn build(records: &[Record], accuracy: f32) -> Grid {
        let reach = |r: &Record| accuracy * r.r;
        let listable = |r: &&Record| {
            let (lo, hi) = (r.p - reach(r), r.p + reach(r));
            reach(r) > 0.0 && lo.is_finite() && hi.is_finite()
        };
        let (mut lo, mut hi) = (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY));
        let mut least = f32::INFINITY;
        for r in records.iter().filter(listable) {
            lo = lo.min(r.p - reach(r));
            hi = hi.max(r.p + reach(r));
            least = least.min(reach(r));
        }
        if !(lo.is_finite() && hi.is_finite() && least.is_finite()) {
            return Grid::default();
        }
        let size = (hi - lo).max_element();
        let level_of = |r: &Record| {
            let steps = (reach(r) / least).log2().floor();
            (steps.max(0.0) as usize).min(MAX_LEVELS - 1)
        };
        let count = records
            .iter()
            .filter(listable)
            .map(level_of)
            .max()
            .unwrap_or(0)
            + 1;
        let mut widest = vec![0.0f32; count];
        for r in records.iter().filter(listable) {
            let l = level_of(r);
            widest[l] = widest[l].max(reach(r));
        }
        // The level's widest reach, and wide enough that every key fits its bits.
        let inv_cells: Vec<f32> = widest
            .iter()
            .map(|&w| 1.0 / w.max(size * 2.0 / MAX_COORD).max(f32::MIN_POSITIVE))
            .collect();
        let origin = lo;
        let coords = |p: Vec3A, inv: f32| {
            let c = ((p - origin) * inv).clamp(Vec3A::ZERO, Vec3A::splat(MAX_COORD - 1.0));
            [c.x as u64, c.y as u64, c.z as u64]
        };
        // (level, cell key, record), sorted: each cell's records in the order they were made.
        let mut listed: Vec<(u32, u64, u32)> = Vec::with_capacity(records.len() * 8);
        for (i, r) in records.iter().enumerate().filter(|(_, r)| listable(r)) {
            let l = level_of(r);
            let (a, b) = (
                coords(r.p - reach(r), inv_cells[l]),
                coords(r.p + reach(r), inv_cells[l]),
            );
            for z in a[2]..=b[2] {
                for y in a[1]..=b[1] {
                    for x in a[0]..=b[0] {
                        listed.push((l as u32, key([x, y, z]), i as u32));
                    }
                }
            }
        }
        listed.sort_unstable();
        let entries = (records.iter().enumerate())
            .map(|(i, r)| Entry::new(i, r))
            .collect();
        let lists = listed.iter().map(|e| e.2).collect();
        let levels = (0..count)
            .map(|l| {
                let from = listed.partition_point(|e| (e.0 as usize) < l);
                let to = listed.partition_point(|e| (e.0 as usize) <= l);
                Level::new(&listed[from..to], from, inv_cells[l])
            })
            .collect();
        Grid {
            origin,
            levels,
            entries,
            lists,
        }
    }

    /// Returns the records listed in the cells holding `p`, level by level (none outside the
    /// grid).
    #[inline]
    pub fn listed(&self, p: Vec3A) -> impl Iterator<Item = &Entry> {
        let rel = p - self.origin;
        self.levels
            .iter()
            .flat_map(move |level| {
                let c = rel * level.inv_cell;
                // NaN fails both tests.
                let inside = c.cmpge(Vec3A::ZERO).all() && c.cmplt(Vec3A::splat(MAX_COORD)).all();
                let slot = inside
                    .then(|| level.find(key([c.x as u64, c.y as u64, c.z as u64])))
                    .flatten();
                match slot {
                    Some(s) => &self.lists[s.start as usize..s.end as usize],
                    None => &[][..],
                }
            })
            .map(|&i| &self.entries[i as usize])
    }
}

/// Returns the key of cell `c` (each coordinate below 2^21).
#[inline(always)]
fn key(c: [u64; 3]) -> u64 {
    c[0] | (c[1] << KEY_BITS) | (c[2] << (2 * KEY_BITS))
}

impl Level {
    /// Returns the level of the sorted `listed` entries (one level's), which start at index
    /// `offset` of the grid's lists.
    fn new(listed: &[(u32, u64, u32)], offset: usize, inv_cell: f32) -> Level {
        let cells = listed.chunk_by(|a, b| a.1 == b.1).count();
        let size = (2 * cells).next_power_of_two().max(2);
        let shift = 64 - size.trailing_zeros();
        let mut slots = vec![
            Slot {
                key: EMPTY,
                start: 0,
                end: 0
            };
            size
        ];
        let mut start = offset;
        for run in listed.chunk_by(|a, b| a.1 == b.1) {
            let key = run[0].1;
            let mut s = home(key, shift);
            while slots[s].key != EMPTY {
                s = (s + 1) & (size - 1);
            }
            slots[s] = Slot {
                key,
                start: start as u32,
                end: (start + run.len()) as u32,
            };
            start += run.len();
        }
        Level {
            inv_cell,
            slots,
            shift,
        }
    }

    /// Returns the slot of cell `key`, if some record meets that cell.
    #[inline(always)]
    fn find(&self, key: u64) -> Option<&Slot> {
        let mask = self.slots.len() - 1;
        let mut s = home(key, self.shift);
        loop {
            let slot = &self.slots[s];
            if slot.key == key {
                return Some(slot);
            }
            if slot.key == EMPTY {
                return None;
            }
            s = (s + 1) & mask;
        }
    }
}
