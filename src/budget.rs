//! One memory budget for everything a scene creates: a byte counter with a limit, charged where
//! each thing is made, so a hostile or careless scene gets an error naming the script line or
//! file at fault instead of the process aborting on a failed allocation.
//!
//! A [`Budget`] is made once per command (`--memory-budget GIB`, by default
//! [`default_limit`]: half the machine's physical memory) and travels with the scene
//! description ([`crate::desc::SceneDesc::budget`]). What is charged, each before (or, for small
//! entries, as) it is allocated, in bytes estimated from the sizes of what is stored:
//! - the description: nodes and their names, children, materials, lights, inline meshes, renders
//!   (charged for good: the description lives as long as the script);
//! - a scene build ([`crate::scene::build`]): placements, instances and the top-level BVH, each
//!   CSG tree expanded per instance, mesh triangles and their BVHs, decoded textures, and the
//!   photons a frame's maps are expected to store; the mesh loaders charge each file's
//!   triangles (glTF per primitive) before they allocate, and textures are charged from their
//!   header's size before they are decoded.
//!
//! A scene build charges an [`Account`], which gives its bytes back when the scene is dropped,
//! so a script that renders many frames is charged for one scene at a time.
//!
//! A budget also carries the scene's read scope ([`Budget::read_scope`]): the folders its mesh
//! files may name material libraries, buffers and images in, so the loaders that charge an
//! account check those names against the same allowance.
//!
//! The Lua state's own memory is bounded apart (the sandbox's limit); limits that bound time or
//! depth rather than memory (node visits, CSG depth, photon counts per light) stay where they are.
//!
//! ```
//! use caustic::budget::Budget;
//! let budget = Budget::new(1000);
//! let scene = budget.account();
//! assert!(scene.try_charge(600, "instances").is_ok());
//! let err = scene.try_charge(600, "triangles").unwrap_err();
//! assert!(err.to_string().starts_with("triangles would take 600 B"));
//! drop(scene);
//! assert_eq!(budget.used(), 0);
//! ```

use crate::error::{Error, Loc};
use std::fmt;
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

/// Fraction of physical memory the default budget allows: the rest is for the system, the Lua
/// state, the film and the renderer's working memory.
const DEFAULT_FRACTION: u64 = 2;
/// Budget assumed when the system does not say how much memory it has.
const FALLBACK_LIMIT: u64 = 8 << 30;

/// Returns the default budget in bytes: half of the machine's physical memory (8 GiB where the
/// system does not say).
pub fn default_limit() -> u64 {
    physical_memory().map_or(FALLBACK_LIMIT, |m| m / DEFAULT_FRACTION)
}

/// Returns the machine's physical memory in bytes, where the system says.
fn physical_memory() -> Option<u64> {
    #[cfg(target_os = "linux")]
    {
        // SAFETY: sysconf only reads system parameters.
        let (pages, size) = unsafe {
            (
                libc::sysconf(libc::_SC_PHYS_PAGES),
                libc::sysconf(libc::_SC_PAGESIZE),
            )
        };
        if pages > 0 && size > 0 {
            return (pages as u64).checked_mul(size as u64);
        }
    }
    None
}

/// A byte counter with a limit, shared by everything one command creates; clones share it.
#[derive(Clone)]
pub struct Budget(Arc<Counter>);

struct Counter {
    limit: u64,
    used: AtomicU64,
    /// The folders the scene's files may name other files in ([`crate::files::ReadScope`]):
    /// the other half of what a scene is allowed, travelling with its bytes.
    scope: crate::files::ReadScope,
}

impl Budget {
    /// Returns a budget of `limit` bytes, nothing charged yet.
    pub fn new(limit: u64) -> Budget {
        Budget::scoped(limit, crate::files::ReadScope::any())
    }

    /// Returns a budget of `limit` bytes for a scene whose files may name only files in
    /// `scope` (its material libraries, glTF buffers and images).
    pub fn scoped(limit: u64, scope: crate::files::ReadScope) -> Budget {
        Budget(Arc::new(Counter {
            limit,
            used: AtomicU64::new(0),
            scope,
        }))
    }

    /// Returns the folders the scene's files may name other files in.
    pub fn read_scope(&self) -> &crate::files::ReadScope {
        &self.0.scope
    }

    /// Returns a budget of [`default_limit`] bytes.
    pub fn machine_default() -> Budget {
        Budget::new(default_limit())
    }

    /// Returns the limit in bytes.
    pub fn limit(&self) -> u64 {
        self.0.limit
    }

    /// Returns the bytes charged and not yet given back.
    pub fn used(&self) -> u64 {
        self.0.used.load(Ordering::Relaxed)
    }

    /// Returns a new, empty account drawing on this budget.
    pub fn account(&self) -> Account {
        Account(Arc::new(Held {
            budget: self.clone(),
            held: AtomicU64::new(0),
        }))
    }

    /// Charges `bytes` for good (what lives as long as the command), or returns what was over.
    pub fn try_charge(&self, bytes: u64, what: impl fmt::Display) -> Result<(), OverBudget> {
        let c = &self.0;
        c.used
            .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |used| {
                used.checked_add(bytes).filter(|&total| total <= c.limit)
            })
            .map(|_| ())
            .map_err(|used| OverBudget {
                what: what.to_string(),
                bytes,
                used,
                limit: c.limit,
            })
    }

    /// Charges `bytes` for good, or returns an error at `at` naming `what` and the amounts.
    pub fn charge(&self, bytes: u64, what: impl fmt::Display, at: At) -> crate::error::Result<()> {
        self.try_charge(bytes, what).map_err(|e| e.at(at))
    }

    fn give_back(&self, bytes: u64) {
        self.0.used.fetch_sub(bytes, Ordering::Relaxed);
    }
}

impl Default for Budget {
    /// Returns [`Budget::machine_default`].
    fn default() -> Budget {
        Budget::machine_default()
    }
}

impl fmt::Debug for Budget {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "Budget({} of {})",
            Bytes(self.used()),
            Bytes(self.limit())
        )
    }
}

/// Charges to a [`Budget`] that are given back when the account (its last clone) is dropped:
/// a scene build's, released with its scene. Clones share one account.
#[derive(Clone)]
pub struct Account(Arc<Held>);

struct Held {
    budget: Budget,
    held: AtomicU64,
}

impl Drop for Held {
    fn drop(&mut self) {
        self.budget.give_back(*self.held.get_mut());
    }
}

impl Account {
    /// Returns the folders the scene's files may name other files in ([`Budget::read_scope`]).
    pub fn read_scope(&self) -> &crate::files::ReadScope {
        self.0.budget.read_scope()
    }

    /// Charges `bytes` to the account, or returns what was over (nothing is charged then).
    pub fn try_charge(&self, bytes: u64, what: impl fmt::Display) -> Result<(), OverBudget> {
        self.0.budget.try_charge(bytes, what)?;
        self.0.held.fetch_add(bytes, Ordering::Relaxed);
        Ok(())
    }

    /// Charges `bytes`, or returns an error at `at` naming `what` and the amounts.
    pub fn charge(&self, bytes: u64, what: impl fmt::Display, at: At) -> crate::error::Result<()> {
        self.try_charge(bytes, what).map_err(|e| e.at(at))
    }

    /// Returns the bytes this account holds.
    pub fn held(&self) -> u64 {
        self.0.held.load(Ordering::Relaxed)
    }

    /// Returns the budget the account draws on.
    pub fn budget(&self) -> &Budget {
        &self.0.budget
    }
}

impl fmt::Debug for Account {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Account({} of {:?})", Bytes(self.held()), self.0.budget)
    }
}

/// Where a charge is made, for its error: a script line, or a file outside any line.
#[derive(Clone, Copy, Debug)]
pub enum At<'a> {
    Script(&'a Loc),
    File(&'a Path),
}

/// A charge the budget could not take: what it was for and the amounts.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct OverBudget {
    /// What the bytes were for ("mesh 0 primitive 3", "the CSG tree of 'u40'").
    pub what: String,
    /// The bytes asked for.
    pub bytes: u64,
    /// The bytes already charged when it was asked.
    pub used: u64,
    /// The budget's limit.
    pub limit: u64,
}

impl OverBudget {
    /// Returns the error this is at `at`: a script fault, or a file error.
    pub fn at(self, at: At) -> Error {
        match at {
            At::Script(loc) => Error::at(loc, self.to_string()),
            At::File(path) => Error::File {
                path: path.to_path_buf(),
                message: self.to_string(),
            },
        }
    }
}

impl fmt::Display for OverBudget {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} would take {}, more than the {} left of the memory budget of {} (--memory-budget GIB raises it)",
            self.what,
            Bytes(self.bytes),
            Bytes(self.limit.saturating_sub(self.used)),
            Bytes(self.limit)
        )
    }
}

impl std::error::Error for OverBudget {}

/// A byte count printed in the largest binary unit that keeps it at least 1 (`1.5 GiB`).
#[derive(Clone, Copy, Debug)]
pub struct Bytes(pub u64);

impl fmt::Display for Bytes {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        const UNITS: [&str; 6] = ["KiB", "MiB", "GiB", "TiB", "PiB", "EiB"];
        if self.0 < 1024 {
            return write!(f, "{} B", self.0);
        }
        let mut v = self.0 as f64 / 1024.0;
        let mut unit = 0;
        // 1023.96 would print as 1024.0: such a value is shown in the next unit.
        while v >= 1023.95 && unit + 1 < UNITS.len() {
            v /= 1024.0;
            unit += 1;
        }
        write!(f, "{v:.1} {}", UNITS[unit])
    }
}

/// Returns `count` items of `T` in bytes, saturating (for charges of counts a file or script
/// gives, which may be absurd).
pub fn bytes_of<T>(count: u64) -> u64 {
    count.saturating_mul(std::mem::size_of::<T>() as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn charges_up_to_the_limit_and_accounts_give_back() {
        let b = Budget::new(100);
        b.try_charge(40, "names").unwrap();
        let a = b.account();
        a.try_charge(60, "instances").unwrap();
        let over = a.try_charge(1, "a node").unwrap_err();
        assert_eq!((over.bytes, over.used, over.limit), (1, 100, 100));
        assert_eq!(a.held(), 60);
        let shared = a.clone();
        drop(a);
        assert_eq!(b.used(), 100, "a clone keeps the account");
        drop(shared);
        assert_eq!(b.used(), 40);
        assert!(b.try_charge(u64::MAX, "overflow").is_err());
        assert_eq!(b.used(), 40);
    }

    #[test]
    fn messages_name_the_amounts() {
        let b = Budget::new(3 << 30);
        b.try_charge(1 << 30, "a").unwrap();
        let e = b.try_charge(5 << 29, "mesh 0 primitive 2").unwrap_err();
        assert_eq!(
            e.to_string(),
            "mesh 0 primitive 2 would take 2.5 GiB, more than the 2.0 GiB left of the memory budget \
             of 3.0 GiB (--memory-budget GIB raises it)"
        );
        assert_eq!(Bytes(512).to_string(), "512 B");
        assert_eq!(Bytes(1536).to_string(), "1.5 KiB");
        assert_eq!(Bytes((1 << 30) - 6000).to_string(), "1.0 GiB");
    }

    #[test]
    fn the_default_is_half_of_physical_memory() {
        let limit = default_limit();
        match physical_memory() {
            Some(m) => assert_eq!(limit, m / 2),
            None => assert_eq!(limit, FALLBACK_LIMIT),
        }
    }
}
