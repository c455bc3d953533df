//! What the system lets this process have, asked before the work that
//! needs it: memory before a large buffer is taken ([`check_memory`],
//! [`buffer`]), open files before many parts are opened
//! ([`raise_open_files`], [`open_files`]). Running out in the middle is
//! an abort with a backtrace (a failed allocation) or "Too many open
//! files" after minutes of work; asked first, it is a one-line refusal
//! that says what is needed, before anything is done.

use std::fmt;

/// Kept free beside a buffer the work needs: the scene, the threads'
/// stacks and allocator arenas, an encoder's blocks, the rows in flight.
pub const MARGIN: u64 = 64 << 20;

/// Memory the work needs and cannot have.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NotEnoughMemory {
    /// Bytes the work needs.
    pub needed: u64,
    /// Bytes this process may still take, where known (a failed
    /// allocation says nothing of what is left).
    pub available: Option<u64>,
}

impl fmt::Display for NotEnoughMemory {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "needs {} of memory ({} bytes)",
            size(self.needed),
            self.needed
        )?;
        match self.available {
            Some(available) => write!(f, ", but only {} is available", size(available)),
            None => write!(f, ", more than the system gives this process"),
        }
    }
}

impl std::error::Error for NotEnoughMemory {}

/// A byte count for people: `3.2 GB`, `512 MB`, `4 kB` (decimal units).
pub fn size(bytes: u64) -> String {
    const UNITS: [&str; 5] = ["bytes", "kB", "MB", "GB", "TB"];
    let mut value = bytes as f64;
    let mut unit = 0;
    while value >= 1000.0 && unit + 1 < UNITS.len() {
        value /= 1000.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{bytes} bytes")
    } else if value < 10.0 {
        format!("{value:.1} {}", UNITS[unit])
    } else {
        format!("{value:.0} {}", UNITS[unit])
    }
}

/// Bytes this process can still take, the least of what each limit
/// leaves: its address-space and data limits (`ulimit -v`, `ulimit -d`,
/// `prlimit --as`) less what it already maps, its control group's memory
/// limit less what the group uses, and the system's available memory and
/// free swap. `None` where none of them can be read (not Linux).
pub fn available_memory() -> Option<u64> {
    let kb = |text: &str, key: &str| -> Option<u64> {
        let line = text.lines().find(|l| l.starts_with(key))?;
        let number = line[key.len()..].trim().trim_end_matches("kB").trim();
        number.parse::<u64>().ok().map(|k| k * 1024)
    };
    let mut least: Option<u64> = None;
    let mut keep = |left: u64| least = Some(least.map_or(left, |l| l.min(left)));
    #[cfg(unix)]
    {
        use rustix::process::{Resource, getrlimit};
        let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
        for (resource, used) in [(Resource::As, "VmSize:"), (Resource::Data, "VmData:")] {
            if let (Some(limit), Some(used)) = (getrlimit(resource).current, kb(&status, used)) {
                keep(limit.saturating_sub(used));
            }
        }
    }
    if let Some(left) = cgroup_memory_left() {
        keep(left);
    }
    let meminfo = std::fs::read_to_string("/proc/meminfo").unwrap_or_default();
    if let Some(available) = kb(&meminfo, "MemAvailable:") {
        keep(available + kb(&meminfo, "SwapFree:").unwrap_or(0));
    }
    least
}

/// What this process's control group may still take: its memory limit
/// less what it uses, not counting the page cache the kernel reclaims
/// for it (a group that has read many files counts them as used).
/// Version 2 (`memory.max`) or version 1 (`memory.limit_in_bytes`), at
/// the group's path or, in a container that shows its group as the root,
/// at the mount itself; `None` where no limit is set.
fn cgroup_memory_left() -> Option<u64> {
    let groups = std::fs::read_to_string("/proc/self/cgroup").ok()?;
    let root = std::path::Path::new("/sys/fs/cgroup");
    let v2 = groups.lines().find_map(|l| l.strip_prefix("0::"));
    let v1 = groups.lines().find_map(|l| {
        let (_, rest) = l.split_once(':')?;
        let (controllers, path) = rest.split_once(':')?;
        controllers
            .split(',')
            .any(|c| c == "memory")
            .then_some(path)
    });
    let number = |dir: &std::path::Path, name: &str| -> Option<u64> {
        std::fs::read_to_string(dir.join(name))
            .ok()?
            .trim()
            .parse()
            .ok()
    };
    let stat = |dir: &std::path::Path, key: &str| -> u64 {
        std::fs::read_to_string(dir.join("memory.stat"))
            .ok()
            .and_then(|text| {
                text.lines()
                    .find_map(|l| l.strip_prefix(key)?.strip_prefix(' ')?.trim().parse().ok())
            })
            .unwrap_or(0)
    };
    let left = |dir: &std::path::Path, limit: &str, usage: &str, cache: &str| {
        let limit = number(dir, limit)?;
        let used = number(dir, usage)?.saturating_sub(stat(dir, cache));
        Some(limit.saturating_sub(used))
    };
    let mut found = None;
    if let Some(path) = v2 {
        for dir in [root.join(path.trim_start_matches('/')), root.to_owned()] {
            found = found.or_else(|| left(&dir, "memory.max", "memory.current", "file"));
        }
    }
    if let Some(path) = v1 {
        let mount = root.join("memory");
        for dir in [mount.join(path.trim_start_matches('/')), mount] {
            found = found.or_else(|| {
                left(
                    &dir,
                    "memory.limit_in_bytes",
                    "memory.usage_in_bytes",
                    "total_cache",
                )
            });
        }
    }
    found
}

/// Refuses work whose buffers take `buffers` bytes where
/// [`available_memory`] says there are fewer than they and [`MARGIN`]
/// beside them (the error names both together).
pub fn check_memory(buffers: u64) -> Result<(), NotEnoughMemory> {
    let needed = buffers.saturating_add(MARGIN);
    match available_memory() {
        Some(available) if needed > available => Err(NotEnoughMemory {
            needed,
            available: Some(available),
        }),
        _ => Ok(()),
    }
}

/// A buffer of `len` zeros, or the error that it cannot be had: the
/// allocation is tried, not assumed (a failed one would abort). Its pages
/// are the system's zeroed ones (calloc's), touched first by whoever
/// writes them: an image's render threads, in parallel, not one thread
/// filling it before the render (5 ms of a 20 ms render of a 2000×2000
/// image on two cores).
pub fn buffer<T: bytemuck::Zeroable>(len: usize) -> Result<Vec<T>, NotEnoughMemory> {
    let needed = (len as u64).saturating_mul(std::mem::size_of::<T>() as u64);
    bytemuck::allocation::try_zeroed_vec(len).map_err(|()| NotEnoughMemory {
        needed,
        available: None,
    })
}

/// Raises this process's soft limit of open files to its hard limit
/// (where that is higher), once; many systems start programs at a soft
/// 1024 under a hard limit far above it. Returns the limits then in force.
pub fn raise_open_files() -> Option<OpenFiles> {
    #[cfg(unix)]
    {
        use rustix::process::{Resource, Rlimit, getrlimit, setrlimit};
        static RAISED: std::sync::Once = std::sync::Once::new();
        RAISED.call_once(|| {
            let limit = getrlimit(Resource::Nofile);
            if limit.current.is_some() && limit.current != limit.maximum {
                // Refused (a hard limit the kernel will not give): the soft
                // one stays, and is what [`open_files`] reports.
                let _ = setrlimit(
                    Resource::Nofile,
                    Rlimit {
                        current: limit.maximum,
                        maximum: limit.maximum,
                    },
                );
            }
        });
    }
    open_files()
}

/// Open files: how many this process has, and may have.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OpenFiles {
    /// Open now.
    pub open: u64,
    /// The soft limit: what may be open at once.
    pub limit: u64,
    /// The hard limit, that the soft one may be raised to (`None`: none).
    pub hard: Option<u64>,
}

/// Files this process has open now and its limits; `None` where they
/// are not known (no limit, or not Unix).
pub fn open_files() -> Option<OpenFiles> {
    #[cfg(unix)]
    {
        use rustix::process::{Resource, getrlimit};
        let limits = getrlimit(Resource::Nofile);
        // The listing itself holds one descriptor while it is read.
        let open = std::fs::read_dir("/proc/self/fd")
            .or_else(|_| std::fs::read_dir("/dev/fd"))
            .ok()?
            .count()
            .saturating_sub(1) as u64;
        Some(OpenFiles {
            open,
            limit: limits.current?,
            hard: limits.maximum,
        })
    }
    #[cfg(not(unix))]
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_read_well() {
        assert_eq!(size(512), "512 bytes");
        assert_eq!(size(3_221_225_472), "3.2 GB");
        assert_eq!(size(805_306_368), "805 MB");
        assert_eq!(size(64 << 20), "67 MB");
    }

    #[test]
    fn what_cannot_be_had_is_refused_not_aborted() {
        assert!(buffer::<u8>(usize::MAX / 2).is_err());
        assert_eq!(buffer::<f64>(3).unwrap(), vec![0.0; 3]);
        if cfg!(target_os = "linux") {
            let available = available_memory().expect("/proc/meminfo at least");
            assert!(available > 1 << 20, "{available}");
            let e = check_memory(u64::MAX / 2).unwrap_err();
            assert!(e.to_string().starts_with("needs "), "{e}");
        }
        assert!(check_memory(1 << 20).is_ok());
        let message = NotEnoughMemory {
            needed: 3_221_225_472,
            available: Some(2_000_000_000),
        }
        .to_string();
        assert_eq!(
            message,
            "needs 3.2 GB of memory (3221225472 bytes), but only 2.0 GB is available"
        );
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn open_files_are_counted() {
        let files = raise_open_files().unwrap();
        assert!(files.open >= 3 && files.limit > files.open, "{files:?}");
        assert_eq!(Some(files.limit), files.hard.or(Some(files.limit)));
    }
}
