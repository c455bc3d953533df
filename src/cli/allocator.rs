//! The process's memory allocator, set once at start ([`tune`]): glibc's
//! malloc with a fixed threshold above which a block gets pages of its own
//! from the kernel, and gives them back when freed.
//!
//! Left to itself, glibc raises that threshold each time such a block is
//! freed (up to 32 MiB), and with it the free memory each thread's arena
//! keeps instead of giving back (twice the threshold). A load of a
//! million spheres frees blocks of 8 and 16 MB (the list of objects as it
//! grows), after which the app's edit, journal and save, each on threads
//! of their own, keep 10–30 MB each that nobody uses again: measured on a
//! million spheres (213.7 MB), the app peaked at 434–439 MB after a save
//! (2.0–2.1× the file; the goal is 2×), 408–410 MB with the threshold fixed
//! at 4 MiB, the edit and the save then adding 1–2 MB. The cost: blocks
//! over 4 MiB are mapped afresh each time: the app's open, picture, edit
//! and save of that scene take 2.6 % longer; the command line's run of it
//! is as fast as before, its peak the same. (At 1 MiB the save's peak is
//! a little lower and the app 7 % slower; at 8 MiB and over, arenas keep
//! most of it again.) docs/bench.md, "The app's memory".
//!
//! A user who sets the allocator's own variables (`MALLOC_MMAP_THRESHOLD_`,
//! `MALLOC_TRIM_THRESHOLD_`, or `malloc` tunables in `GLIBC_TUNABLES`)
//! keeps them. Other C libraries (musl) and systems: nothing is set.

/// The size from which a block is mapped on its own and unmapped when
/// freed: above the pieces a load reads (1 MiB and what is carried over),
/// below the lists a million objects make (8 MB and up).
#[cfg(all(target_os = "linux", target_env = "gnu"))]
const MMAP_THRESHOLD: libc::c_int = 4 << 20;

/// Fixes glibc's mmap threshold at [`MMAP_THRESHOLD`] unless the user set
/// the allocator's variables. Called first thing in `main`, before any
/// thread.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
pub fn tune() {
    let set_by_user = std::env::var_os("MALLOC_MMAP_THRESHOLD_").is_some()
        || std::env::var_os("MALLOC_TRIM_THRESHOLD_").is_some()
        || std::env::var("GLIBC_TUNABLES").is_ok_and(|t| t.contains("malloc."));
    if set_by_user {
        return;
    }
    // SAFETY: mallopt only sets a parameter of glibc's allocator, which
    // takes its own lock to do so; a value it refuses leaves the default
    // (it returns 0, and the allocator works as before).
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, MMAP_THRESHOLD);
    }
}

#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
pub fn tune() {}
