//! When to rewrite a file that grows with the run (`history.csv`, `newton.csv`).
//!
//! Those tables are rewritten whole (atomically, see [`crate::atomic`]) so that a running job can
//! be watched and a crash leaves complete files. Rewritten after every increment, their cost grows
//! with the number of rows: a 4000-increment run spent 90 % of its 11.8 s rewriting them. A
//! rewrite is now due when [`INTERVAL`] has passed since the last one, and at least twenty times
//! the time the last one took, so that rewriting costs at most about 5 % of a run; the caller
//! writes once more at the end (or on failure).

use std::time::{Duration, Instant};

/// The shortest time between two rewrites of a table.
pub const INTERVAL: Duration = Duration::from_secs(1);

/// The time of a table's last rewrite and what it cost.
#[derive(Debug, Clone, Copy, Default)]
pub struct Throttle {
    last: Option<Instant>,
    cost: Duration,
}

impl Throttle {
    /// Whether a rewrite is due: none yet, or [`INTERVAL`] and twenty times the last one's cost
    /// since it ended.
    #[must_use]
    pub fn due(&self) -> bool {
        self.last
            .is_none_or(|t| t.elapsed() >= INTERVAL.max(20 * self.cost))
    }

    /// Records a rewrite that started at `started` and has just ended.
    pub fn wrote(&mut self, started: Instant) {
        let now = Instant::now();
        self.cost = now - started;
        self.last = Some(now);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_rewrite_is_due_first_then_after_the_interval() {
        let mut t = Throttle::default();
        assert!(t.due());
        t.wrote(Instant::now());
        assert!(!t.due(), "just written");
        // As if the last rewrite ended more than the interval ago.
        t.last = Instant::now().checked_sub(INTERVAL + Duration::from_millis(10));
        assert!(t.due());
        // A slow rewrite (0.1 s) waits twenty times as long (2 s), not the interval.
        t.cost = Duration::from_millis(100);
        t.last = Instant::now().checked_sub(INTERVAL + Duration::from_millis(10));
        assert!(!t.due());
    }
}
