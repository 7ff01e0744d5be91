//! Memory: huge pages for the big arrays that rendering reads at random (BVH nodes, triangle
//! blocks and photon maps), and the process's peak resident size for `--stats`
//! ([`peak_resident_kib`]), kept flat over a progressive render's passes
//! ([`return_big_blocks`]).
//!
//! Why: ray traversal and photon lookups jump between cache lines all over arrays of tens of
//! megabytes, so with 4 KiB pages almost every read also misses the TLB, and under a hypervisor a
//! TLB miss costs a two-level page walk. Measured on the project's 2-core VM (a pointer chase
//! through a shuffled array): 2 MB array 58 ns per read with 4 KiB pages, 29 ns with 2 MiB pages;
//! 23 MB array 169 ns and 149 ns; and with 2 MiB pages two processes chasing at once no longer
//! slow each other down.
//!
//! How: Linux backs memory with transparent huge pages only where a program asks
//! (`/sys/kernel/mm/transparent_hugepage/enabled` is usually `madvise`). Our arrays are ordinary
//! `Vec`s, so instead of a custom allocator we ask in one of two ways:
//! - [`huge_vec`] / [`reserve_huge`] advise huge pages on capacity not yet written
//!   (`MADV_HUGEPAGE`), which then faults in as huge pages at no extra cost: for arrays sized up
//!   front, like the mesh BVH's (this saved 0.25–0.39 s per build of a 2M-triangle mesh);
//! - [`prefer_huge_pages`] collapses the whole 2 MiB pages of a finished array into huge pages
//!   (`MADV_COLLAPSE`, Linux 6.1; it copies, about 0.4 ms per MB): for arrays that grew by
//!   pushing.
//!
//! Either is advice: on other systems, older kernels or when the kernel has no huge page free,
//! nothing happens and nothing changes but speed. `CAUSTIC_HUGE_PAGES=0` in the environment turns it off (to measure what it gives).

/// Size of a transparent huge page on x86-64 and most AArch64 kernels.
const HUGE_PAGE: usize = 2 << 20;

/// Asks the kernel to back the whole huge pages that `data` covers with huge pages (see the
/// module doc). Arrays smaller than two huge pages are left alone.
pub fn prefer_huge_pages<T>(data: &[T]) {
    if let Some((start, len)) = whole_huge_pages(data) {
        collapse(start, len);
    }
}

/// Returns the start and length of the whole huge pages inside `data`, or None when it spans
/// fewer than two huge pages (or huge pages are turned off).
fn whole_huge_pages<T>(data: &[T]) -> Option<(usize, usize)> {
    let len = std::mem::size_of_val(data);
    if len < 2 * HUGE_PAGE || !enabled() {
        return None;
    }
    let start = (data.as_ptr() as usize).next_multiple_of(HUGE_PAGE);
    let end = (data.as_ptr() as usize + len) / HUGE_PAGE * HUGE_PAGE;
    (end > start).then_some((start, end - start))
}

/// Returns an empty vector with room for `capacity` elements whose whole huge pages the kernel is
/// asked to back with huge pages when they are first written (`MADV_HUGEPAGE`). Unlike
/// [`prefer_huge_pages`], which copies finished arrays into huge pages, this costs nothing: the
/// pages are faulted in as huge ones in the first place. Use it for arrays built in one go.
pub fn huge_vec<T>(capacity: usize) -> Vec<T> {
    let mut v = Vec::with_capacity(capacity);
    reserve_huge(&mut v, capacity);
    v
}

/// Reserves room for `additional` more elements in `v` and advises huge pages for the whole
/// huge pages of the spare room (see [`huge_vec`]); pages already written stay as they are.
pub fn reserve_huge<T>(v: &mut Vec<T>, additional: usize) {
    v.reserve(additional);
    if let Some((start, len)) = whole_huge_pages(v.spare_capacity_mut()) {
        advise(start, len);
    }
}

fn enabled() -> bool {
    static ENABLED: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *ENABLED.get_or_init(|| std::env::var_os("CAUSTIC_HUGE_PAGES").is_none_or(|v| v != "0"))
}

#[cfg(target_os = "linux")]
fn advise(start: usize, len: usize) {
    // SAFETY: `start..start + len` lies inside one live allocation (the vector's spare
    // capacity); MADV_HUGEPAGE only changes how pages not yet written will be mapped, never any
    // contents, and an error leaves the mapping as it was, so the result is ignored.
    unsafe {
        libc::madvise(start as *mut libc::c_void, len, libc::MADV_HUGEPAGE);
    }
}

#[cfg(not(target_os = "linux"))]
fn advise(_start: usize, _len: usize) {}

#[cfg(target_os = "linux")]
fn collapse(start: usize, len: usize) {
    // The kernel's value (include/uapi/asm-generic/mman-common.h), not in every libc.
    const MADV_COLLAPSE: libc::c_int = 25;
    // SAFETY: `start..start + len` lies inside one live allocation (the caller's slice), and
    // MADV_COLLAPSE only changes how that memory is mapped, never its contents; an error (an old
    // kernel, no free huge page) leaves the mapping as it was, so the result is ignored.
    unsafe {
        libc::madvise(start as *mut libc::c_void, len, MADV_COLLAPSE);
    }
}

#[cfg(not(target_os = "linux"))]
fn collapse(_start: usize, _len: usize) {}

/// Gives the whole pages inside `data` back to the system (`MADV_DONTNEED`): they stop counting
/// as resident, and read as zeros if touched again. For a large array whose contents are done
/// with before the array itself can be freed (a photon map's build records, copied into the
/// map from the end). Elsewhere than Linux it does nothing.
///
/// # Safety
/// Every all-zero bit pattern must be a valid `T`: the pages discarded read as zeros.
pub unsafe fn discard<T>(data: &mut [T]) {
    #[cfg(target_os = "linux")]
    {
        const PAGE: usize = 4096;
        let begin = data.as_ptr() as usize;
        let start = begin.next_multiple_of(PAGE);
        let end = (begin + std::mem::size_of_val(data)) / PAGE * PAGE;
        if end > start {
            // SAFETY: `start..end` lies inside `data`, which the caller holds mutably, and
            // MADV_DONTNEED on private memory only replaces its pages with zero-filled ones,
            // which the caller says are valid values; an error leaves the pages as they were.
            unsafe {
                libc::madvise(start as *mut libc::c_void, end - start, libc::MADV_DONTNEED);
            }
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = data;
}

/// Returns the most memory the process has held resident so far, in KiB (Linux's `VmHWM`), or
/// `None` where the system does not say.
pub fn peak_resident_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// Size from which glibc serves an allocation by its own `mmap` and unmaps it when freed.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
const MMAP_THRESHOLD: libc::c_int = 1 << 20;

/// Makes the allocator give every block of a megabyte or more back to the system when it is
/// freed. Why: glibc raises its mmap threshold to the size of each mmapped block freed, after
/// which blocks that size come from the heap, where freed ones stay resident and fragment; over
/// the passes of a progressive render, whose photon maps differ in size from pass to pass, the
/// peak resident size then crept up by about 20 KB per pass (300,000 photons per pass, two
/// threads). A fixed threshold stops it. Call once, before any thread starts; elsewhere than
/// glibc it does nothing.
pub fn return_big_blocks() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets an allocator parameter; it is called before threads start.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, MMAP_THRESHOLD);
    }
}

/// Gives the allocator's free memory back to the system (glibc's `malloc_trim`, which also
/// releases free pages inside its heaps, not only at their tops); elsewhere does nothing.
/// Called between the passes of a progressive render: each pass frees its maps, and without
/// this the pieces left free in the worker threads' heaps stayed resident and the peak crept
/// up from pass to pass.
pub fn release_free_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim only returns free memory to the system; any thread may call it.
    unsafe {
        libc::malloc_trim(0);
    }
}
