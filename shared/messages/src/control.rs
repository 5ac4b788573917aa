//! Run-level messages: health, progress watermarks, run events and control.

use iceoryx2::prelude::ZeroCopySend;

use crate::{Flags, Header, Role};

/// `run/events`, on change.
pub const RUN_EVENTS_SERVICE: &str = "run/events";

/// The health service of a role: `<role>/health`.
pub fn health_service(role: &str) -> String {
    format!("{role}/health")
}

/// The progress (watermark) service of a role: `<role>/progress`.
pub fn progress_service(role: &str) -> String {
    format!("{role}/progress")
}

/// The control (request-response) service of a role: `<role>/control`.
pub fn control_service(role: &str) -> String {
    format!("{role}/control")
}

/// Process states reported in [`Health::state`] and [`RunEvent`].
pub mod state {
    /// Starting up, ports not yet open.
    pub const STARTING: u32 = 0;
    /// Ports open, waiting for input.
    pub const READY: u32 = 1;
    /// Processing and publishing.
    pub const RUNNING: u32 = 2;
    /// Following inputs without publishing (hot-swap standby).
    pub const STANDBY: u32 = 3;
    /// Inputs ended; draining.
    pub const DRAINING: u32 = 4;
    /// Stopped.
    pub const STOPPED: u32 = 5;
}

message! {
    /// Per-process health, 1 Hz.
    #[wire(type_name = "nauta.Health.v1", size = 104)]
    pub struct Health {
        /// Common header; `stamp_ns` is the last input stamp processed.
        pub header: Header,
        /// Messages received and accepted.
        pub inputs: u64,
        /// Messages published.
        pub outputs: u64,
        /// Messages rejected by validation.
        pub rejected: u64,
        /// Messages lost: sequence gaps seen on inputs plus outputs given up
        /// (back-pressure deadline in `sim`, overflow in `wall`).
        pub dropped: u64,
        /// Wall time since the process started, ns.
        pub uptime_ns: u64,
        /// Process id.
        pub pid: u32,
        /// [`state`] value.
        pub state: u32,
        /// Variant name, NUL-padded UTF-8.
        pub variant: [u8; 24],
    }
}

message! {
    /// A watermark: the publisher has nothing earlier than `header.stamp_ns`
    /// still to send. With the end-of-stream flag, it will send nothing more.
    #[wire(type_name = "nauta.Progress.v1", size = 40)]
    pub struct Progress {
        /// Common header; `stamp_ns` is the watermark.
        pub header: Header,
        /// Messages this publisher has sent on its data services so far.
        pub published: u64,
    }
}

impl Progress {
    /// A watermark at `stamp_ns` from `role` (instance filled in by the publisher).
    pub fn at(stamp_ns: u64, role: Role, published: u64) -> Self {
        Progress {
            header: Header::new(stamp_ns, 0, role, 0),
            published,
        }
    }

    /// The end of `role`'s stream, after its last stamp `stamp_ns`.
    pub fn end_of_stream(stamp_ns: u64, role: Role, published: u64) -> Self {
        let mut p = Self::at(stamp_ns, role, published);
        p.header.flags |= Flags::END_OF_STREAM.0;
        p
    }
}

/// Kinds of [`RunEvent`].
pub mod event_kind {
    /// A process was started.
    pub const STARTED: u32 = 1;
    /// A process opened its ports and is ready for input.
    pub const READY: u32 = 2;
    /// A process exited (see `exit_code`).
    pub const EXITED: u32 = 3;
    /// A process was restarted.
    pub const RESTARTED: u32 = 4;
    /// A process was swapped for another variant.
    pub const SWAPPED: u32 = 5;
    /// The run ended.
    pub const RUN_ENDED: u32 = 6;
    /// The aided INS advises surfacing: its predicted horizontal error
    /// passed the manifest's threshold (paper 002's "foresee the moment to
    /// emerge"); published once per crossing, at the solution's stamp.
    pub const SURFACING_ADVISED: u32 = 7;
}

message! {
    /// A lifecycle event of the run.
    #[wire(type_name = "nauta.RunEvent.v1", size = 112)]
    pub struct RunEvent {
        /// Common header; `stamp_ns` is the run-clock time of the event (last stamp seen).
        pub header: Header,
        /// [`event_kind`] value.
        pub kind: u32,
        /// Role the event is about.
        pub role: u32,
        /// Instance of that role.
        pub instance: u32,
        /// Process id.
        pub pid: u32,
        /// Exit code for `EXITED` (-signal when killed by a signal).
        pub exit_code: i32,
        /// Zero.
        pub pad: u32,
        /// Process name in the manifest, NUL-padded.
        pub process: [u8; 32],
        /// Variant, NUL-padded.
        pub variant: [u8; 24],
    }
}

/// Commands in [`ControlRequest::command`].
pub mod command {
    /// Follow inputs without publishing.
    pub const STANDBY: u32 = 1;
    /// Start publishing from the next stamp after `ControlRequest::stamp_ns`.
    pub const ACTIVATE: u32 = 2;
    /// Stop publishing after `ControlRequest::stamp_ns`.
    pub const DEACTIVATE: u32 = 3;
    /// Publish a snapshot now.
    pub const SNAPSHOT_NOW: u32 = 4;
    /// Drain and exit.
    pub const STOP: u32 = 5;
}

message! {
    /// A launcher command to one process.
    #[wire(type_name = "nauta.ControlRequest.v1", size = 48)]
    pub struct ControlRequest {
        /// Common header.
        pub header: Header,
        /// [`command`] value.
        pub command: u32,
        /// Zero.
        pub pad: u32,
        /// Stamp boundary for activate/deactivate, ns.
        pub boundary_stamp_ns: u64,
    }
}

message! {
    /// The answer to a [`ControlRequest`].
    #[wire(type_name = "nauta.ControlResponse.v1", size = 48)]
    pub struct ControlResponse {
        /// Common header.
        pub header: Header,
        /// 0 accepted, otherwise an error code.
        pub status: u32,
        /// Process state after the command.
        pub state: u32,
        /// Last stamp processed, ns.
        pub last_stamp_ns: u64,
    }
}

/// Commands in [`PipelineRequest::command`] (`nauta stop|restart|swap`).
pub mod pipeline_command {
    /// Stop the whole run in order (as SIGINT would).
    pub const STOP: u32 = 1;
    /// Restart one process (warm start from its latest snapshot).
    pub const RESTART: u32 = 2;
    /// Swap one process for another variant.
    pub const SWAP: u32 = 3;
}

/// Answers in [`PipelineResponse::status`].
pub mod pipeline_status {
    /// Done (or started: a swap completes asynchronously).
    pub const OK: u32 = 0;
    /// No process of that name in the run.
    pub const UNKNOWN_PROCESS: u32 = 1;
    /// The process's binary does not implement that variant.
    pub const UNKNOWN_VARIANT: u32 = 2;
    /// Not possible for this process now (a source, the run is ending, ...).
    pub const REFUSED: u32 = 3;
    /// Unknown command.
    pub const UNKNOWN_COMMAND: u32 = 4;
}

message! {
    /// A command from another shell to the launcher of a running pipeline
    /// (`launcher/control/0`).
    #[wire(type_name = "nauta.PipelineRequest.v1", size = 96)]
    pub struct PipelineRequest {
        /// Common header.
        pub header: Header,
        /// [`pipeline_command`] value.
        pub command: u32,
        /// Zero.
        pub pad: u32,
        /// Process name in the manifest, NUL-padded (restart, swap).
        pub process: [u8; 32],
        /// Variant to swap to, NUL-padded.
        pub variant: [u8; 24],
    }
}

message! {
    /// The launcher's answer to a [`PipelineRequest`].
    #[wire(type_name = "nauta.PipelineResponse.v1", size = 72)]
    pub struct PipelineResponse {
        /// Common header.
        pub header: Header,
        /// [`pipeline_status`] value.
        pub status: u32,
        /// Zero.
        pub pad: u32,
        /// A short explanation, NUL-padded.
        pub detail: [u8; 32],
    }
}
