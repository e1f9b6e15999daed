//! What the sweep binaries (`rig-sweep`, `rig-coverage`) share: the seeds
//! and the `finrs` binary they run, and a pool of threads for the
//! sessions.

use std::path::PathBuf;
use std::sync::Mutex;

use crate::sweep::Scenario;

/// The sweep's seeds and the `finrs` binary that runs each session.
#[derive(clap::Args, Clone, Debug)]
pub struct SweepArgs {
    /// First seed (the hidden-effect tests use seeds below 1000).
    #[arg(long, default_value_t = 10_000)]
    pub first_seed: u64,
    /// Sessions.
    #[arg(long, default_value_t = 100)]
    pub sessions: usize,
    /// The `finrs` binary that runs each session.
    #[arg(long, default_value = "target/release/finrs")]
    pub finrs: PathBuf,
    /// Sessions run at once.
    #[arg(long, default_value_t = 2)]
    pub jobs: usize,
}

impl SweepArgs {
    /// Refuses what cannot run: no thread, or no `finrs` binary.
    pub fn check(&self) -> anyhow::Result<()> {
        anyhow::ensure!(self.jobs >= 1, "--jobs must be at least 1");
        anyhow::ensure!(
            self.finrs.is_file(),
            "{} is not a file: build it (cargo build --release -p finrs) or give --finrs",
            self.finrs.display()
        );
        Ok(())
    }
}

/// `one` of each of `items` on `jobs` threads, the results in the items'
/// order (a session's `finrs` run is the time; the threads only wait).
pub fn on_threads<S: Sync, T: Send>(
    items: &[S],
    jobs: usize,
    one: impl Fn(&S) -> T + Sync,
) -> Vec<T> {
    let next = Mutex::new(items.iter().enumerate());
    let done = Mutex::new(Vec::with_capacity(items.len()));
    std::thread::scope(|scope| {
        for _ in 0..jobs.max(1) {
            scope.spawn(|| loop {
                let Some((i, item)) = next.lock().expect("no panics under the lock").next() else {
                    break;
                };
                let out = one(item);
                done.lock()
                    .expect("no panics under the lock")
                    .push((i, out));
            });
        }
    });
    let mut done = done.into_inner().expect("no panics under the lock");
    done.sort_by_key(|(i, _)| *i);
    done.into_iter().map(|(_, out)| out).collect()
}

/// `one` of each of the sweep's `scenarios` on `jobs` threads, in seed
/// order; a session that fails is named on stderr with its error and left
/// out of the results.
pub fn each_session<T: Send>(
    scenarios: &[Scenario],
    jobs: usize,
    one: impl Fn(&Scenario) -> anyhow::Result<T> + Sync,
) -> Vec<T> {
    on_threads(scenarios, jobs, |s| {
        one(s).map_err(|e| eprintln!("seed {}: {e:#}", s.seed)).ok()
    })
    .into_iter()
    .flatten()
    .collect()
}

/// One task's share of a sweep, `K/N` (1-based, as a job array numbers
/// its tasks): the scenarios at places `K, K + N, K + 2N, …` of the plan,
/// so that `N` tasks together run each once and each gets every row of the
/// plan's turns alike.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// This task, 1..=`count`.
    pub index: usize,
    /// Tasks in all.
    pub count: usize,
}

impl std::str::FromStr for Shard {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let rule = "a shard is K/N, task K of N, 1 <= K <= N";
        let (k, n) = s.split_once('/').ok_or_else(|| format!("`{s}`: {rule}"))?;
        let whole = |x: &str| {
            x.trim()
                .parse::<usize>()
                .map_err(|e| format!("`{s}`: {rule} ({e})"))
        };
        let (index, count) = (whole(k)?, whole(n)?);
        if index == 0 || index > count {
            return Err(format!("`{s}`: {rule}"));
        }
        Ok(Shard { index, count })
    }
}

impl Shard {
    /// What a shard's run prints at its end: `done` of its `planned`
    /// sessions kept in `kept_in`, and how the shards merge.
    pub fn summary(self, done: usize, planned: usize, kept_in: &std::path::Path) -> String {
        format!(
            "shard {}/{}: {done} of {planned} sessions kept in {}; the same command without --shard, with --kept-only, merges the shards",
            self.index,
            self.count,
            kept_in.display()
        )
    }

    /// This task's share of `plan`, in the plan's order.
    pub fn take<T>(self, plan: Vec<T>) -> Vec<T> {
        plan.into_iter()
            .enumerate()
            .filter(|(i, _)| i % self.count == self.index - 1)
            .map(|(_, x)| x)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shards_of_a_plan_run_each_scenario_once() {
        let plan: Vec<u64> = (100..117).collect();
        for count in [1, 2, 3, 17, 20] {
            let mut all: Vec<u64> = (1..=count)
                .flat_map(|index| Shard { index, count }.take(plan.clone()))
                .collect();
            all.sort_unstable();
            assert_eq!(all, plan, "{count} shards");
        }
        assert_eq!(
            "2/3".parse::<Shard>().unwrap().take(plan.clone()),
            [101, 104, 107, 110, 113, 116]
        );
    }

    #[test]
    fn a_shard_out_of_its_range_is_refused_with_the_rule() {
        assert_eq!("4/4".parse(), Ok(Shard { index: 4, count: 4 }));
        for bad in ["0/4", "5/4", "1/0", "3", "a/4", "-1/4", ""] {
            let err = bad.parse::<Shard>().unwrap_err();
            assert!(err.contains("K/N") && err.contains(bad), "{bad}: {err}");
        }
    }

    #[test]
    fn every_item_runs_once_and_the_results_keep_the_items_order() {
        let items: Vec<u64> = (0..17).collect();
        let out = on_threads(&items, 3, |&x| {
            // Uneven work, so the threads finish out of order.
            std::thread::sleep(std::time::Duration::from_millis((17 - x) % 5));
            x * x
        });
        assert_eq!(out, items.iter().map(|x| x * x).collect::<Vec<_>>());
        assert!(on_threads(&[] as &[u64], 2, |&x| x).is_empty());
    }

    #[test]
    fn a_missing_binary_or_no_thread_is_refused_by_name() {
        let args = SweepArgs {
            first_seed: 10_000,
            sessions: 1,
            finrs: PathBuf::from("no/such/finrs"),
            jobs: 1,
        };
        let err = args.check().unwrap_err().to_string();
        assert!(err.contains("no/such/finrs is not a file"), "{err}");
        let err = SweepArgs { jobs: 0, ..args }
            .check()
            .unwrap_err()
            .to_string();
        assert!(err.contains("--jobs"), "{err}");
    }
}
