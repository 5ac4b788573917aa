//! The runtime every nauta process is built on (DESIGN §5-7): node creation in a
//! per-run namespace, one definition per service (its QoS), typed publishers and
//! subscribers with sequence-gap counting and back-pressure deadlines, the event
//! loop that ends cleanly on SIGINT/SIGTERM, the run clock, the ordered
//! multi-input merge, health reporting and dead-node cleanup, and the estimator
//! shell ([`shell`]) that runs every role's estimator with all of that.
//!
//! Estimation code never depends on this crate; a service binary is a thin shell
//! that wires [`Context`] ports to a pure estimator.

pub mod clock;
pub mod context;
pub mod control;
pub mod describe;
pub mod event_loop;
pub mod health;
pub mod manifest;
pub mod manifest_limits;
pub mod merge;
pub mod namespace;
pub mod ports;
pub mod process;
pub mod run_files;
pub mod services;
pub mod shell;

pub use clock::{ClockMode, Pacer};
pub use context::Context;
pub use control::{ControlClient, ControlServer, PipelineClient, PipelineServer};
pub use describe::{Describe, PortDescription};
pub use event_loop::{EventLoop, LoopExit, Wake};
pub use health::HealthReporter;
pub use manifest::{Manifest, RestartPolicy};
pub use merge::OrderedMerge;
pub use namespace::Namespace;
pub use ports::{Connect, Inbox, Publisher, Subscriber};
pub use process::ProcessArgs;
pub use services::ServiceSpec;
pub use shell::{Lifecycle, Shell};

/// iceoryx2's inter-process service type, used everywhere.
pub type Ipc = iceoryx2::service::ipc::Service;
