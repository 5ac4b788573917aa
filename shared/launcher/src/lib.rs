//! The launcher and supervisor of a pipeline (DESIGN §5), as a library: the
//! `nauta` binary's `launch`, `check`, `status`, `stop`, `restart`, `swap`,
//! `record`, `replay` and `log info` are thin calls into it.
//!
//! - [`launch`]: a manifest checked and started, the run to its end, and its
//!   summary ([`summary`]);
//! - [`supervisor`]: the processes, their restarts, swaps and stops;
//!   [`children`]: starting and reaping them;
//! - [`monitor`]: the launcher's taps on the pipeline (health, progress, the
//!   truth and estimates for the summary's errors);
//! - [`pipeline`]: a running pipeline's status file and control requests;
//!   [`rundir`]: the private per-user run directory;
//! - [`logcmd`]: recording, replaying and describing recordings.

pub mod children;
pub mod launch;
pub mod logcmd;
pub mod monitor;
pub mod pipeline;
pub mod rundir;
pub mod summary;
pub mod supervisor;
