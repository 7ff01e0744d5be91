//! The traversal stack: slots that are never initialised up front, so a ray pays nothing for the
//! capacity it does not use (zeroing a fixed array cost every ray about a kilobyte of stores).

use std::mem::MaybeUninit;

/// Entries that live on the thread stack; deeper trees (pathological scenes) use the heap.
const INLINE: usize = 256;

/// A child waiting on the traversal stack, with the ray's entry distance into its box.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Entry {
    /// A node reference as stored in [`super::wide::Node::child`].
    pub child: u32,
    pub t: f32,
}

/// A stack over borrowed, possibly uninitialised slots.
pub(super) struct Stack<'a> {
    slots: &'a mut [MaybeUninit<Entry>],
    /// Slots `..len` hold entries written by `push` or `insert_sorted`; the rest may be
    /// uninitialised.
    len: usize,
}

impl Stack<'_> {
    /// Runs `f` with an empty stack of at least `capacity` slots.
    #[inline(always)]
    pub fn with_capacity<R>(capacity: usize, f: impl FnOnce(Stack) -> R) -> R {
        if capacity <= INLINE {
            let mut slots = [const { MaybeUninit::uninit() }; INLINE];
            f(Stack {
                slots: &mut slots,
                len: 0,
            })
        } else {
            let mut heap = Vec::new();
            heap.resize_with(capacity, MaybeUninit::uninit);
            f(Stack {
                slots: &mut heap,
                len: 0,
            })
        }
    }

    /// A stack over `slots` holding the entries in `slots[..len]` (a stream lane's stack, kept
    /// between the lane's steps).
    ///
    /// # Safety
    /// `slots[..len]` must have been written, by a stack over the same slots or otherwise.
    #[inline(always)]
    pub unsafe fn over(slots: &mut [MaybeUninit<Entry>], len: usize) -> Stack<'_> {
        debug_assert!(len <= slots.len());
        Stack { slots, len }
    }

    /// Returns the number of entries.
    #[inline(always)]
    pub fn len(&self) -> usize {
        self.len
    }

    /// Returns entry `i`.
    ///
    /// # Panics
    /// When `i >= len`.
    #[inline(always)]
    fn get(&self, i: usize) -> Entry {
        assert!(i < self.len);
        // SAFETY: slots below `len` have been written (the invariant of `len`).
        unsafe { self.slots[i].assume_init() }
    }

    /// Pushes `e`.
    ///
    /// # Panics
    /// When the stack is full (the tree is deeper than the capacity allows: a bug).
    #[inline(always)]
    pub fn push(&mut self, e: Entry) {
        self.slots[self.len].write(e);
        self.len += 1;
    }

    /// Pushes `e` among the entries from `base` up, which stay sorted by `t`, nearest on top.
    #[inline(always)]
    pub fn insert_sorted(&mut self, base: usize, e: Entry) {
        let mut j = self.len;
        self.push(e);
        while j > base && self.get(j - 1).t < e.t {
            let moved = self.get(j - 1);
            self.slots[j].write(moved);
            j -= 1;
        }
        self.slots[j].write(e);
    }

    /// Pops entries until one entered no further than `tmax` (a nearer hit culls the others),
    /// and returns it, if any.
    #[inline(always)]
    pub fn pop_within(&mut self, tmax: f32) -> Option<Entry> {
        while let Some(e) = self.pop() {
            if e.t <= tmax {
                return Some(e);
            }
        }
        None
    }

    /// Pops the top entry, if any.
    #[inline(always)]
    pub fn pop(&mut self) -> Option<Entry> {
        let top = self.len.checked_sub(1)?;
        let e = self.get(top);
        self.len = top;
        Some(e)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sorted_inserts_pop_nearest_first() {
        for cap in [4, INLINE + 1] {
            Stack::with_capacity(cap, |mut s| {
                s.push(Entry { child: 9, t: 100.0 });
                for (c, t) in [(1, 3.0), (2, 1.0), (3, 2.0)] {
                    s.insert_sorted(1, Entry { child: c, t });
                }
                let order: Vec<u32> = std::iter::from_fn(|| s.pop()).map(|e| e.child).collect();
                assert_eq!(order, [2, 3, 1, 9]);
            });
        }
    }
}
