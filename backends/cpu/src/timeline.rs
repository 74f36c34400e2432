//! Timeline semaphores between queue threads, as Vulkan has them.

use std::sync::{Condvar, Mutex};
use std::time::{Duration, Instant};

/// A monotonically increasing counter that threads wait on.
#[derive(Default)]
pub struct Timeline {
    value: Mutex<u64>,
    changed: Condvar,
}

/// Why a wait ended without reaching its value.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WaitError {
    TimedOut,
    Aborted,
}

impl Timeline {
    pub fn signal(&self, value: u64) {
        let mut v = self.value.lock().unwrap_or_else(|e| e.into_inner());
        *v = (*v).max(value);
        self.changed.notify_all();
    }

    /// Wakes every waiter so it can see an abort flag.
    pub fn wake(&self) {
        self.changed.notify_all();
    }

    /// Waits until the value reaches `value`, `abort()` turns true, or `timeout` passes.
    pub fn wait(
        &self,
        value: u64,
        timeout: Duration,
        abort: impl Fn() -> bool,
    ) -> Result<(), WaitError> {
        let deadline = Instant::now() + timeout;
        let mut v = self.value.lock().unwrap_or_else(|e| e.into_inner());
        while *v < value {
            if abort() {
                return Err(WaitError::Aborted);
            }
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return Err(WaitError::TimedOut);
            }
            let slice = left.min(Duration::from_millis(50));
            v = self
                .changed
                .wait_timeout(v, slice)
                .unwrap_or_else(|e| e.into_inner())
                .0;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    #[test]
    fn wait_returns_once_signalled() {
        let t = Arc::new(Timeline::default());
        let t2 = t.clone();
        let h = std::thread::spawn(move || t2.wait(3, Duration::from_secs(5), || false));
        t.signal(1);
        t.signal(3);
        assert_eq!(h.join().unwrap(), Ok(()));
    }

    #[test]
    fn wait_times_out_instead_of_hanging() {
        let t = Timeline::default();
        assert_eq!(
            t.wait(1, Duration::from_millis(20), || false),
            Err(WaitError::TimedOut)
        );
        assert_eq!(
            t.wait(1, Duration::from_secs(5), || true),
            Err(WaitError::Aborted)
        );
    }
}
