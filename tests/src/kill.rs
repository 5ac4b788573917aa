//! A kill -9 whose victim's last messages reach the test first.
//!
//! The launcher removes a dead process's shared memory as soon as it sees the
//! exit, and a subscriber loses what it had not yet taken from a removed
//! publisher. A live consumer takes a message within one wake-up; a test's
//! follower on a loaded machine may not. So a test that checks every stamp
//! downstream stops the victim first (SIGSTOP), takes everything it had
//! published, and only then kills it: what the restarted instance must
//! continue from is then exactly what the follower saw.

use crate::Watchdog;
use std::time::Duration;

/// The state letter of process `pid` in `/proc/PID/stat`, if it exists.
fn state_of(pid: u32) -> Option<char> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    stat.rsplit_once(") ")?.1.chars().next()
}

/// Stops `pid`, waits (under the watchdog) until it is stopped, calls
/// `drain` to take what it published, then kills it with SIGKILL.
pub fn kill_9_after_draining(wd: &Watchdog, pid: u32, mut drain: impl FnMut()) {
    // SAFETY: kill(2) on a process of this test's own run.
    assert_eq!(
        unsafe { libc::kill(pid as i32, libc::SIGSTOP) },
        0,
        "SIGSTOP {pid}"
    );
    while !matches!(state_of(pid), Some('T' | 't') | None) {
        wd.check();
        std::thread::sleep(Duration::from_millis(1));
    }
    // Stopped: every send it completed is in the subscribers' queues.
    drain();
    // SAFETY: as above.
    assert_eq!(
        unsafe { libc::kill(pid as i32, libc::SIGKILL) },
        0,
        "SIGKILL {pid}"
    );
}
