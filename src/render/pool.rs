//! The one kind of thread pool renders run on: [`RenderPool`]. Every pool
//! of render threads is built here — the command line's `--threads`
//! ([`super::render`] and its siblings), the bench and the study (built
//! before their clocks start, see [`crate::render::measure`](mod@crate::render::measure)), and the app's render
//! worker (named threads, all the cores, and a smaller one while the user
//! drags).

use super::{RenderError, RenderOptions};

/// The threads a render runs on: a pool of its own for a thread count, or
/// the pool the caller already runs in (rayon's global one, a thread a
/// core, unless installed in another).
pub struct RenderPool {
    pool: Option<rayon::ThreadPool>,
}

impl RenderPool {
    /// A pool of `threads` threads (checked as `--threads` is), or none of
    /// its own for `None`.
    pub fn new(threads: Option<usize>) -> Result<RenderPool, RenderError> {
        Self::build(threads, None)
    }

    /// No pool of its own: work runs in the pool of its caller.
    pub fn current() -> RenderPool {
        RenderPool { pool: None }
    }

    /// A pool of `threads` threads named `name-0`, `name-1`…, for a
    /// program that keeps one (the app's worker).
    pub fn named(threads: usize, name: &'static str) -> Result<RenderPool, RenderError> {
        Self::build(Some(threads), Some(name))
    }

    fn build(
        threads: Option<usize>,
        name: Option<&'static str>,
    ) -> Result<RenderPool, RenderError> {
        let Some(threads) = threads else {
            return Ok(RenderPool::current());
        };
        RenderOptions {
            threads: Some(threads),
            ..RenderOptions::default()
        }
        .validate()?;
        let mut builder = rayon::ThreadPoolBuilder::new().num_threads(threads);
        if let Some(name) = name {
            builder = builder.thread_name(move |i| format!("{name}-{i}"));
        }
        let pool = builder
            .build()
            .map_err(|source| RenderError::ThreadPool { threads, source })?;
        Ok(RenderPool { pool: Some(pool) })
    }

    /// The threads `work` runs on in [`RenderPool::install`].
    pub fn threads(&self) -> usize {
        self.pool.as_ref().map_or_else(
            rayon::current_num_threads,
            rayon::ThreadPool::current_num_threads,
        )
    }

    /// Runs `work` on the pool's threads.
    pub fn install<R: Send>(&self, work: impl FnOnce() -> R + Send) -> R {
        match &self.pool {
            Some(pool) => pool.install(work),
            None => work(),
        }
    }
}

/// The render threads that use every core: one a core.
pub fn all_cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pool_runs_work_on_its_threads_and_checks_its_count() {
        let pool = RenderPool::named(3, "test").unwrap();
        assert_eq!(pool.threads(), 3);
        let name = pool.install(|| std::thread::current().name().map(str::to_owned));
        assert!(name.is_some_and(|n| n.starts_with("test-")));
        assert!(matches!(
            RenderPool::new(Some(0)),
            Err(RenderError::NoThreads)
        ));
        assert!(matches!(
            RenderPool::new(Some(super::super::max_threads() + 1)),
            Err(RenderError::TooManyThreads(_))
        ));
        assert_eq!(
            RenderPool::new(None).unwrap().threads(),
            rayon::current_num_threads()
        );
    }
}
