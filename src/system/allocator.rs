//! The process's memory allocator, where it is glibc's malloc: set once
//! at start ([`tune`]): a fixed threshold above which a block gets pages
//! of its own from the kernel and gives them back when freed, and under an
//! address-space limit one arena for every thread; and asked to give back
//! what it holds free after a large piece of work ([`give_back`]).
//!
//! The threshold. Left to itself, glibc raises it each time such a block
//! is freed (up to 32 MiB), and with it the free memory each thread's
//! arena keeps instead of giving back (twice the threshold). A load of a
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
//! The arenas. Each thread that allocates takes an arena of its own, and
//! each arena reserves 64 MiB of address space, used or not. Under `ulimit
//! -v` (`prlimit --as`) that is the limit spent by threads that need a
//! few kB: a 4096² depth pass, 134 MB, fitted in 256 MB with the threads
//! rayon starts for it, and was refused with `--threads 4` three runs out
//! of four (the pool's threads reserving their arenas before the image
//! was taken), `--threads 8` every time. With an address-space limit set,
//! every thread allocates from the one arena: they wait on its lock when
//! they allocate at once (the command line's run of a million spheres
//! under a limit took 1.56 s against 1.19 s without one, the threads
//! parsing its pieces taking turns; a render allocates little: the
//! mirrors at `--aa 2` as fast), and never reserve what they do not use.
//!
//! Giving back. Below the threshold, a thread's arena gives pages back to
//! the system only from its top: a few live bytes above the blocks a save
//! freed keep them all. The app's save of 200 000 spheres left 5–6 MB that
//! way one run in three (0.8–1.9 MB the other runs); `malloc_trim` hands
//! back the free pages of every arena wherever they are, in 0.2–0.5 ms.
//! The app calls it as each save ends (`SaveJob::spawn`).
//!
//! A user who sets the allocator's own variables (`MALLOC_MMAP_THRESHOLD_`,
//! `MALLOC_TRIM_THRESHOLD_`, `MALLOC_ARENA_MAX`, or `malloc` tunables in
//! `GLIBC_TUNABLES`) keeps them. Other C libraries (musl) and systems:
//! nothing is set, nothing given back.

// The calls into glibc are this module's only `unsafe`, each with its
// safety argument.
#![allow(unsafe_code)]

/// The size from which a block is mapped on its own and unmapped when
/// freed: above the pieces a load reads (1 MiB and what is carried over),
/// below the lists a million objects make (8 MB and up).
#[cfg(all(target_os = "linux", target_env = "gnu"))]
const MMAP_THRESHOLD: libc::c_int = 4 << 20;

/// Fixes glibc's mmap threshold at `MMAP_THRESHOLD` (4 MiB), and under an
/// address-space limit keeps to one arena, unless the user set the
/// allocator's variables. Called first thing in `main`, before any thread.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
pub fn tune() {
    let set_by_user = [
        "MALLOC_MMAP_THRESHOLD_",
        "MALLOC_TRIM_THRESHOLD_",
        "MALLOC_ARENA_MAX",
    ]
    .iter()
    .any(|name| std::env::var_os(name).is_some())
        || std::env::var("GLIBC_TUNABLES").is_ok_and(|t| t.contains("malloc."));
    if set_by_user {
        return;
    }
    let limited = rustix::process::getrlimit(rustix::process::Resource::As)
        .current
        .is_some();
    // SAFETY: mallopt only sets parameters of glibc's allocator, which
    // takes its own lock to do so; a value it refuses leaves the default
    // (it returns 0, and the allocator works as before).
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, MMAP_THRESHOLD);
        if limited {
            libc::mallopt(libc::M_ARENA_MAX, 1);
        }
    }
}

#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
pub fn tune() {}

/// Hands the pages the allocator holds free, in every arena, back to the
/// system: after a piece of work that allocated much on a thread of its
/// own and freed it (a save), so that it does not stay resident.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
pub fn give_back() {
    // SAFETY: malloc_trim takes each arena's lock and only releases pages
    // of free chunks (madvise) or shrinks the top; live blocks are
    // untouched. Its result (whether anything was released) is not needed.
    unsafe {
        libc::malloc_trim(0);
    }
}

#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
pub fn give_back() {}
