//! A short list of results computed lately, the newest first, shared by
//! every thread of the process: what [`super::kept_modes`] and
//! [`super::drying`] keep. An entry is kept whole and never changed, so a
//! thread that panicked holding the list left it usable.

use std::sync::{Mutex, MutexGuard, PoisonError};

/// At most `most` entries, the newest first.
pub(super) struct Recent<T> {
    entries: Mutex<Vec<T>>,
    most: usize,
}

impl<T> Recent<T> {
    /// An empty list of at most `most` entries (`const`: for a `static`).
    pub(super) const fn new(most: usize) -> Self {
        Recent {
            entries: Mutex::new(Vec::new()),
            most,
        }
    }

    /// The first answer `f` gives, newest entry first.
    pub(super) fn find_map<R>(&self, f: impl FnMut(&T) -> Option<R>) -> Option<R> {
        self.lock().iter().find_map(f)
    }

    /// Keeps `entry` as the newest, the oldest dropped past `most`. The
    /// caller computes it outside the lock: two threads may compute one
    /// result at once, which costs the work twice, never a wrong answer.
    pub(super) fn keep(&self, entry: T) {
        let mut entries = self.lock();
        entries.insert(0, entry);
        entries.truncate(self.most);
    }

    fn lock(&self) -> MutexGuard<'_, Vec<T>> {
        self.entries.lock().unwrap_or_else(PoisonError::into_inner)
    }
}

#[cfg(test)]
mod tests {
    use super::Recent;

    #[test]
    fn the_newest_is_found_first_and_the_oldest_dropped() {
        let recent = Recent::new(2);
        assert_eq!(recent.find_map(|&x: &i32| Some(x)), None);
        for x in [1, 2, 3] {
            recent.keep(x);
        }
        assert_eq!(recent.find_map(|&x| Some(x)), Some(3));
        assert_eq!(recent.find_map(|&x| (x == 2).then_some(x)), Some(2));
        assert_eq!(recent.find_map(|&x| (x == 1).then_some(x)), None);
    }
}
