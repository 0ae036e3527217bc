//! A team of threads that stays awake between the parallel loops of a step.
//!
//! A step has five short parallel loops (half kick and drift, the skin check, the pair
//! forces, the gathering of the chunks' halo buffers, the second half kick), each of tens to
//! hundreds of microseconds on a few thousand particles. Handing a loop to rayon's pool
//! costs a wake-up of its sleeping threads each time, measured at 15–40 µs per
//! `rayon::join` on a 2-core virtual machine — as much as the loop itself. A [`Team`]
//! keeps its threads spinning on a generation counter for a while after each job
//! (0.3–0.4 µs per hand-over on the same machine) and parks them when none comes, so an
//! idle simulation does not hold the cores.
//!
//! The work of a job is split statically: member `t` of `m` takes items `t, t + m, …`, so
//! the split, and with it every floating-point sum, depends only on the team size. A job
//! must not start rayon work of its own: a member is not a rayon thread and would use the
//! global pool.

use std::panic::{AssertUnwindSafe, catch_unwind, resume_unwind};
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, PoisonError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// How long a member spins for the next job before it parks.
const SPIN: Duration = Duration::from_micros(100);

/// Spins between looks at the clock (or, for the caller, between yields).
const SPINS_PER_LOOK: u32 = 64;

/// Whether teams made from now on run their members' parts in turn on the calling thread.
static IN_TURN: AtomicBool = AtomicBool::new(false);

/// Makes the teams made from now on run the parts of their members one after another on
/// the calling thread (`true`) instead of on worker threads: the same split of the work and
/// the same bits, without the hand-overs between threads. For counting the instructions of
/// a thread count under valgrind, which runs threads one at a time and would count the
/// members' spin-waits as work.
pub fn set_members_in_turn(on: bool) {
    IN_TURN.store(on, Ordering::Relaxed);
}

/// A team of `threads` members: the calling thread and `threads − 1` worker threads (or,
/// after [`set_members_in_turn`], the calling thread alone, taking each member's part in
/// turn).
pub struct Team {
    shared: Arc<Shared>,
    workers: Vec<JoinHandle<()>>,
    /// Members, the calling thread included.
    members: usize,
}

/// The job of the current generation, type-erased: `call(data, member)`.
#[derive(Clone, Copy)]
struct Job {
    data: *const (),
    call: unsafe fn(*const (), usize),
}

// SAFETY: `data` points to a `Sync` closure that outlives the job (`Team::run` waits for
// every member before it returns), so sharing the pointer between threads is sound.
unsafe impl Send for Job {}

/// State shared by the caller and the workers.
struct Shared {
    /// Generation of the current job; a worker runs a job when it sees a new one.
    generation: AtomicU64,
    /// The job of the current generation.
    job: Mutex<Option<Job>>,
    /// Workers that have not finished the current job.
    pending: AtomicUsize,
    /// Whether a worker's part of the current job panicked.
    panicked: AtomicBool,
    /// Whether a job is running (a nested or concurrent call then runs serially).
    busy: AtomicBool,
    /// Whether the team is being dropped.
    shutdown: AtomicBool,
    /// Per worker: whether it is parked (or about to park).
    parked: Vec<AtomicBool>,
}

impl Team {
    /// A team of `threads` members (at least one: the calling thread alone, no workers).
    pub fn new(threads: usize) -> Team {
        Team::made(threads, IN_TURN.load(Ordering::Relaxed))
    }

    /// A team of `threads` members, with worker threads unless `in_turn`.
    fn made(threads: usize, in_turn: bool) -> Team {
        let members = threads.max(1);
        let workers = if in_turn { 0 } else { members - 1 };
        let shared = Arc::new(Shared {
            generation: AtomicU64::new(0),
            job: Mutex::new(None),
            pending: AtomicUsize::new(0),
            panicked: AtomicBool::new(false),
            busy: AtomicBool::new(false),
            shutdown: AtomicBool::new(false),
            parked: (0..workers).map(|_| AtomicBool::new(false)).collect(),
        });
        let workers = (0..workers)
            .map(|w| {
                let shared = Arc::clone(&shared);
                std::thread::Builder::new()
                    .name(format!("rheodem-team-{}", w + 1))
                    .spawn(move || work(&shared, w))
                    .expect("the operating system starts a team thread")
            })
            .collect();
        Team {
            shared,
            workers,
            members,
        }
    }

    /// Members of the team, the calling thread included.
    pub fn threads(&self) -> usize {
        self.members
    }

    /// Runs `f(t)` once for every member `t` in `0..threads()` (member 0 on the calling
    /// thread) and returns when all have finished. A panic in any member is raised again
    /// here. A call made while the team is busy (from inside a job, or from another
    /// thread), or by a team without worker threads, runs every member's part on the
    /// calling thread, in order.
    pub fn run<F: Fn(usize) + Sync>(&self, f: F) {
        let shared = &*self.shared;
        if self.workers.is_empty() || shared.busy.swap(true, Ordering::Acquire) {
            (0..self.threads()).for_each(f);
            return;
        }
        /// Calls the closure behind `data` for `member`.
        ///
        /// # Safety
        /// `data` must point to a live `F`.
        unsafe fn call<F: Fn(usize) + Sync>(data: *const (), member: usize) {
            // SAFETY: the caller passes the `F` that `Team::run` published.
            unsafe { (*data.cast::<F>())(member) }
        }
        *lock(&shared.job) = Some(Job {
            data: (&raw const f).cast(),
            call: call::<F>,
        });
        shared.pending.store(self.workers.len(), Ordering::Relaxed);
        shared.generation.fetch_add(1, Ordering::SeqCst);
        for (w, handle) in self.workers.iter().enumerate() {
            if shared.parked[w].load(Ordering::SeqCst) {
                handle.thread().unpark();
            }
        }
        let own = catch_unwind(AssertUnwindSafe(|| f(0)));
        // `f` must outlive every worker's use of it: wait even if our part panicked.
        let mut spins = 0u32;
        while shared.pending.load(Ordering::Acquire) != 0 {
            spins = spins.wrapping_add(1);
            if spins.is_multiple_of(SPINS_PER_LOOK) {
                std::thread::yield_now();
            } else {
                std::hint::spin_loop();
            }
        }
        *lock(&shared.job) = None;
        let worker_panicked = shared.panicked.swap(false, Ordering::Relaxed);
        shared.busy.store(false, Ordering::Release);
        if let Err(payload) = own {
            resume_unwind(payload);
        }
        assert!(!worker_panicked, "a team thread panicked");
    }

    /// Calls `f` on every item, member `t` of `m` taking items `t, t + m, …`.
    pub fn for_each<T: Send, F: Fn(&mut T) + Sync>(&self, items: &mut [T], f: F) {
        /// The items' base pointer, shared by the members.
        struct Items<T>(*mut T);
        // SAFETY: each member dereferences only its own indices (below), so no item is
        // reached from two threads; `T: Send` lets it be used on another thread.
        unsafe impl<T: Send> Sync for Items<T> {}
        let (base, len, m) = (Items(items.as_mut_ptr()), items.len(), self.threads());
        let base = &base;
        self.run(|t| {
            for k in (t..len).step_by(m) {
                // SAFETY: `k < len`, and index `k` belongs to member `k % m` alone.
                f(unsafe { &mut *base.0.add(k) });
            }
        });
    }

    /// Length of the contiguous pieces that split `n` items among the members, at least
    /// `min_len` each (so that a short loop stays on fewer threads).
    pub fn piece_len(&self, n: usize, min_len: usize) -> usize {
        n.div_ceil(self.threads()).max(min_len).max(1)
    }
}

impl Drop for Team {
    fn drop(&mut self) {
        self.shared.shutdown.store(true, Ordering::SeqCst);
        for handle in self.workers.drain(..) {
            handle.thread().unpark();
            // A worker catches the panics of its jobs, so joining cannot fail on them.
            let _ = handle.join();
        }
    }
}

impl std::fmt::Debug for Team {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Team")
            .field("threads", &self.threads())
            .finish()
    }
}

/// The job slot, whatever a panicking holder left in it (a plain `Copy` value).
fn lock(job: &Mutex<Option<Job>>) -> std::sync::MutexGuard<'_, Option<Job>> {
    job.lock().unwrap_or_else(PoisonError::into_inner)
}

/// The loop of worker `w` (member `w + 1`): wait for a new generation, run its job.
fn work(shared: &Shared, w: usize) {
    let mut seen = 0;
    loop {
        let mut spins = 0u32;
        let mut since = Instant::now();
        loop {
            let generation = shared.generation.load(Ordering::Acquire);
            if generation != seen {
                seen = generation;
                break;
            }
            if shared.shutdown.load(Ordering::Acquire) {
                return;
            }
            spins = spins.wrapping_add(1);
            if !spins.is_multiple_of(SPINS_PER_LOOK) || since.elapsed() < SPIN {
                std::hint::spin_loop();
                continue;
            }
            // Park, unless a job or the shutdown came meanwhile (the caller reads
            // `parked` after publishing, so one of the two sides sees the other).
            shared.parked[w].store(true, Ordering::SeqCst);
            if shared.generation.load(Ordering::SeqCst) == seen
                && !shared.shutdown.load(Ordering::SeqCst)
            {
                std::thread::park();
            }
            shared.parked[w].store(false, Ordering::SeqCst);
            since = Instant::now();
        }
        let job = *lock(&shared.job);
        if let Some(job) = job {
            // SAFETY: the job was published for this generation and `Team::run` keeps
            // its closure alive until `pending` reaches zero.
            let outcome = catch_unwind(|| unsafe { (job.call)(job.data, w + 1) });
            if outcome.is_err() {
                shared.panicked.store(true, Ordering::Relaxed);
            }
        }
        shared.pending.fetch_sub(1, Ordering::AcqRel);
    }
}

/// A simulation's team, made on first use with the thread count of the rayon pool in
/// scope, and made again if that count changes. Not part of the simulation state: a clone
/// or a deserialised simulation starts without one.
#[derive(Debug, Default)]
pub struct TeamSlot(Option<Team>);

impl TeamSlot {
    /// The team, with as many members as the current rayon pool has threads.
    pub fn get(&mut self) -> &Team {
        let threads = rayon::current_num_threads().max(1);
        if self.0.as_ref().is_none_or(|t| t.threads() != threads) {
            self.0 = Some(Team::new(threads));
        }
        self.0.as_ref().expect("made just above")
    }
}

impl Clone for TeamSlot {
    fn clone(&self) -> TeamSlot {
        TeamSlot(None)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::AtomicU32;

    #[test]
    fn every_member_runs_once_per_job() {
        for threads in 1..=4 {
            let team = Team::new(threads);
            for _ in 0..1000 {
                let hits: Vec<AtomicU32> = (0..threads).map(|_| AtomicU32::new(0)).collect();
                team.run(|t| {
                    hits[t].fetch_add(1, Ordering::Relaxed);
                });
                assert!(hits.iter().all(|h| h.load(Ordering::Relaxed) == 1));
            }
        }
    }

    #[test]
    fn for_each_visits_every_item_once_with_the_static_split() {
        let team = Team::new(3);
        let mut items: Vec<(usize, Option<usize>)> = (0..10).map(|k| (k, None)).collect();
        let member = std::thread::current().id();
        team.for_each(&mut items, |item| {
            // Member 0 (this thread) takes items 0, 3, 6, 9.
            let mine = std::thread::current().id() == member;
            assert_eq!(mine, item.0 % 3 == 0);
            item.1 = Some(item.0 * item.0);
        });
        for (k, sq) in items {
            assert_eq!(sq, Some(k * k));
        }
    }

    #[test]
    fn workers_park_when_idle_and_wake_for_the_next_job() {
        let team = Team::new(2);
        let sum = AtomicU32::new(0);
        team.run(|t| {
            sum.fetch_add(t as u32 + 1, Ordering::Relaxed);
        });
        // Long enough for the worker to stop spinning and park.
        std::thread::sleep(SPIN * 20);
        assert!(team.shared.parked[0].load(Ordering::SeqCst));
        team.run(|t| {
            sum.fetch_add(t as u32 + 1, Ordering::Relaxed);
        });
        assert_eq!(sum.load(Ordering::Relaxed), 6);
    }

    #[test]
    fn a_panic_in_a_worker_reaches_the_caller_and_the_team_stays_usable() {
        let team = Team::new(2);
        let caught = catch_unwind(AssertUnwindSafe(|| {
            team.run(|t| {
                if t == 1 {
                    panic!("member 1 fails");
                }
            })
        }));
        assert!(caught.is_err());
        let count = AtomicU32::new(0);
        team.run(|_| {
            count.fetch_add(1, Ordering::Relaxed);
        });
        assert_eq!(count.load(Ordering::Relaxed), 2);
    }

    #[test]
    fn a_nested_call_runs_serially_instead_of_deadlocking() {
        let team = Team::new(2);
        let count = AtomicU32::new(0);
        team.run(|_| {
            team.run(|_| {
                count.fetch_add(1, Ordering::Relaxed);
            });
        });
        assert_eq!(count.load(Ordering::Relaxed), 4);
    }

    #[test]
    fn members_in_turn_take_the_same_parts_on_the_calling_thread() {
        let team = Team::made(4, true);
        assert_eq!(team.threads(), 4);
        assert!(team.workers.is_empty());
        let caller = std::thread::current().id();
        let mut items: Vec<(usize, Option<usize>)> = (0..10).map(|k| (k, None)).collect();
        team.for_each(&mut items, |item| {
            assert_eq!(std::thread::current().id(), caller);
            item.1 = Some(item.0 + 1);
        });
        assert!(items.iter().all(|&(k, v)| v == Some(k + 1)));
    }

    #[test]
    fn pieces_cover_the_items_and_respect_the_minimum() {
        let team = Team::new(2);
        assert_eq!(team.piece_len(4096, 512), 2048);
        assert_eq!(team.piece_len(600, 512), 512);
        assert_eq!(team.piece_len(0, 0), 1);
    }
}
