//! The process loop (DESIGN §6): wait on the inputs' events and a periodic tick
//! with an iceoryx2 WaitSet, drain everything available per wake-up, and end
//! cleanly on SIGINT/SIGTERM (the WaitSet installs iceoryx2's signal handling,
//! so the node's resources are released on the way out).

use std::ops::ControlFlow;
use std::time::Duration;

use iceoryx2::prelude::*;
use iceoryx2::waitset::WaitSetRunResult;

use crate::Ipc;
use crate::ports::Inbox;

/// Why the handler is called.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wake {
    /// Inputs may have data (also called once at start).
    Data,
    /// The periodic tick (health, cleanup).
    Tick,
}

/// How the loop ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LoopExit {
    /// The handler asked to stop.
    Finished,
    /// SIGINT or SIGTERM.
    Signal,
}

/// Waits on inboxes and a tick.
#[derive(Debug)]
pub struct EventLoop {
    tick: Duration,
}

impl EventLoop {
    /// A loop that ticks every `tick` (1 s for health).
    pub fn new(tick: Duration) -> Self {
        EventLoop { tick }
    }

    /// Runs until the handler breaks or a termination signal arrives. The
    /// handler gets `Wake::Data` once at start and after every wake-up by an
    /// inbox, and `Wake::Tick` every tick; it should drain all its inputs.
    pub fn run(
        &self,
        inboxes: &[&Inbox],
        mut handler: impl FnMut(Wake) -> anyhow::Result<ControlFlow<()>>,
    ) -> anyhow::Result<LoopExit> {
        let waitset = WaitSetBuilder::new()
            .create::<Ipc>()
            .map_err(|e| anyhow::anyhow!("cannot create the WaitSet: {e:?}"))?;
        let mut guards = Vec::with_capacity(inboxes.len());
        for inbox in inboxes {
            guards.push(
                waitset
                    .attach_notification(&inbox.listener)
                    .map_err(|e| anyhow::anyhow!("cannot wait on {}: {e:?}", inbox.name))?,
            );
        }
        let tick_guard = waitset
            .attach_interval(self.tick)
            .map_err(|e| anyhow::anyhow!("cannot attach the tick: {e:?}"))?;

        if handler(Wake::Data)?.is_break() {
            return Ok(LoopExit::Finished);
        }
        loop {
            let mut data = false;
            let mut tick = false;
            let result = waitset
                .wait_and_process_once(|id: WaitSetAttachmentId<Ipc>| {
                    if id.has_event_from(&tick_guard) {
                        tick = true;
                    } else {
                        data = true;
                    }
                    CallbackProgression::Continue
                })
                .map_err(|e| anyhow::anyhow!("WaitSet failed: {e:?}"))?;
            match result {
                WaitSetRunResult::TerminationRequest => return Ok(LoopExit::Signal),
                // The wait was interrupted (EINTR: SIGSTOP/SIGCONT, SIGCHLD, a
                // debugger). That is no request to end: wait again. A SIGINT
                // or SIGTERM that interrupted it is reported by the next wait
                // as a termination request (iceoryx2 keeps the signal).
                WaitSetRunResult::Interrupt => continue,
                WaitSetRunResult::AllEventsHandled | WaitSetRunResult::StopRequest => {}
            }
            if data {
                // Consume the notifications first: anything published after this
                // point notifies again, so no wake-up is lost.
                for inbox in inboxes {
                    inbox.clear();
                }
                if handler(Wake::Data)?.is_break() {
                    return Ok(LoopExit::Finished);
                }
            }
            if tick && handler(Wake::Tick)?.is_break() {
                return Ok(LoopExit::Finished);
            }
        }
    }
}
