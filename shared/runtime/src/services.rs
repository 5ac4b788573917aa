//! Every service of DESIGN §4, defined once: name, type and QoS. iceoryx2 takes the
//! QoS of whoever creates a service as a requirement for everyone who opens it,
//! so every participant must open a service through the function defined here.

use core::marker::PhantomData;

use nauta_messages::*;

/// Publishers allowed per service: a role, its hot-swap standby, a replay and a test tap.
pub const MAX_PUBLISHERS: usize = 4;
/// Subscribers allowed per service: consumers, logger, launcher monitor, a standby.
pub const MAX_SUBSCRIBERS: usize = 16;
/// Nodes allowed per service.
pub const MAX_NODES: usize = 32;
/// Publishers allowed on `run/events` and other run-wide services: every process.
pub const MAX_RUN_PUBLISHERS: usize = 32;

/// Delivery of a data service.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Delivery {
    /// Follows the run's clock: lossless with back-pressure in `sim`, bounded
    /// buffers that overwrite the oldest sample in `wall`.
    ByClock,
    /// Always overwrites the oldest sample: a publisher never waits (health,
    /// progress, events: nothing may stall on them).
    Lossy,
}

/// A publish-subscribe service: name (without the run namespace), message type and QoS.
#[derive(Debug)]
pub struct ServiceSpec<M: Message> {
    /// Service name without the namespace, e.g. `sensor/imu`.
    pub name: String,
    /// Subscriber queue length, samples.
    pub buffer: usize,
    /// Samples kept for late subscribers.
    pub history: usize,
    /// Publishers allowed.
    pub max_publishers: usize,
    /// How it delivers.
    pub delivery: Delivery,
    _m: PhantomData<M>,
}

impl<M: Message> Clone for ServiceSpec<M> {
    fn clone(&self) -> Self {
        ServiceSpec {
            name: self.name.clone(),
            buffer: self.buffer,
            history: self.history,
            max_publishers: self.max_publishers,
            delivery: self.delivery,
            _m: PhantomData,
        }
    }
}

impl<M: Message> ServiceSpec<M> {
    fn data(name: &str, buffer: usize) -> Self {
        ServiceSpec {
            name: name.to_owned(),
            buffer,
            history: history_for(buffer),
            max_publishers: MAX_PUBLISHERS,
            delivery: Delivery::ByClock,
            _m: PhantomData,
        }
    }

    fn latest(name: &str, max_publishers: usize) -> Self {
        ServiceSpec {
            name: name.to_owned(),
            buffer: 16,
            history: 1,
            max_publishers,
            delivery: Delivery::Lossy,
            _m: PhantomData,
        }
    }

    /// The type name on the wire.
    pub fn type_name(&self) -> &'static str {
        M::TYPE_NAME
    }
}

/// Queue length for 100 Hz streams: 20 s of data, so a consumer can batch
/// and a restarted one can replay (see [`history_for`]).
const FAST: usize = 2048;
/// Queue length for ≤ 10 Hz streams.
const SLOW: usize = 256;

/// Samples a data service keeps for a subscriber that joins late: a process
/// restarted (or swapped in) mid-run warm-starts from its last snapshot (every
/// second of the run clock) and replays its inputs from there, so the history
/// must reach back from the moment the new instance subscribes to the
/// snapshot: the snapshot's age (up to 1 s), how far the dead instance lagged
/// behind its inputs, and the restart, all in the run's clock. At `--rate 10`
/// each 0.1 s of wall time is 1 s of history. Measured at 10x with four
/// estimators on a loaded 2-core machine (docs/design-notes.md, "Acoustic
/// positioning"): the ains lagged the sensor by up to 4 s and a restart took
/// 0.2-0.4 s, so the 4.8 s this history once held lost 29-177 `ains/nav`
/// stamps per late restart. 15.4 s at 100 Hz, 19.2 s at 10 Hz; three
/// quarters of the queue, so that the live samples arriving before the new
/// instance's first drain do not overwrite the oldest of its history.
fn history_for(buffer: usize) -> usize {
    buffer / 4 * 3
}

/// `sensor/imu`.
pub fn imu() -> ServiceSpec<ImuSample> {
    ServiceSpec::data(IMU_SERVICE, FAST)
}
/// `sensor/dvl`.
pub fn dvl() -> ServiceSpec<DvlSample> {
    ServiceSpec::data(DVL_SERVICE, SLOW)
}
/// `sensor/depth`.
pub fn depth() -> ServiceSpec<DepthSample> {
    ServiceSpec::data(DEPTH_SERVICE, SLOW)
}
/// `sensor/gps`.
pub fn gps() -> ServiceSpec<GpsFix> {
    ServiceSpec::data(GPS_SERVICE, SLOW)
}
/// `sensor/ahrs`.
pub fn ahrs() -> ServiceSpec<AhrsSample> {
    ServiceSpec::data(AHRS_SERVICE, SLOW)
}
/// `sensor/propeller`.
pub fn propeller() -> ServiceSpec<PropellerSample> {
    ServiceSpec::data(PROPELLER_SERVICE, SLOW)
}
/// `sensor/modem`.
pub fn modem() -> ServiceSpec<BuoyRange> {
    ServiceSpec::data(MODEM_SERVICE, SLOW)
}
/// `sensor/lbl`.
pub fn lbl_reply() -> ServiceSpec<LblReply> {
    ServiceSpec::data(LBL_REPLY_SERVICE, SLOW)
}
/// `lbl/interrogate`.
pub fn lbl_interrogate() -> ServiceSpec<LblInterrogation> {
    ServiceSpec::data(LBL_INTERROGATE_SERVICE, SLOW)
}
/// `sim/truth`.
pub fn truth() -> ServiceSpec<TruthState> {
    ServiceSpec::data(TRUTH_SERVICE, FAST)
}
/// `attitude/estimate`.
pub fn attitude_estimate() -> ServiceSpec<AttitudeEstimate> {
    ServiceSpec::data(ATTITUDE_ESTIMATE_SERVICE, FAST)
}
/// `ains/nav`.
pub fn nav_solution() -> ServiceSpec<NavSolution> {
    ServiceSpec::data(NAV_SOLUTION_SERVICE, FAST)
}
/// `positioning/fix`.
pub fn position_fix() -> ServiceSpec<PositionFix> {
    ServiceSpec::data(POSITION_FIX_SERVICE, SLOW)
}
/// `lbl/nav`.
pub fn lbl_solution() -> ServiceSpec<LblSolution> {
    ServiceSpec::data(LBL_SOLUTION_SERVICE, SLOW)
}
/// Queue length for snapshots. The shell publishes one at every whole second
/// of the run's clock that a batch crosses, and one drain of a full data
/// queue is a batch of up to 25.6 s (`SLOW` at 10 Hz; `FAST` at 100 Hz is
/// 20.5 s), so a queue of 16 lost snapshots in a recording even when the
/// logger kept up (`ains/snapshot`, 266 of 2,603 in a `--fast` survey whose
/// ains waited on the positioning and then drained its backlog). 64 holds two
/// such batches; a snapshot is at most 2.4 kB, so 16 subscribers cost 2.4 MB.
const SNAPSHOTS: usize = 64;

/// `<role>/snapshot`: the latest is kept for late subscribers (history 1).
pub fn snapshot<M: Message>(role: Role) -> ServiceSpec<M> {
    ServiceSpec {
        buffer: SNAPSHOTS,
        ..ServiceSpec::latest(&snapshot_service(role.name()), MAX_PUBLISHERS)
    }
}
/// `<role>/health`.
pub fn health(role: Role) -> ServiceSpec<Health> {
    ServiceSpec::latest(&health_service(role.name()), MAX_PUBLISHERS)
}
/// `<role>/progress`: watermarks, lossless like the data they qualify.
pub fn progress(role: Role) -> ServiceSpec<Progress> {
    ServiceSpec::data(&progress_service(role.name()), SLOW)
}
/// `run/events`: every process publishes; never blocks anybody.
pub fn run_events() -> ServiceSpec<RunEvent> {
    ServiceSpec {
        name: RUN_EVENTS_SERVICE.to_owned(),
        buffer: 256,
        history: 0,
        max_publishers: MAX_RUN_PUBLISHERS,
        delivery: Delivery::Lossy,
        _m: PhantomData,
    }
}

/// A service definition without its Rust type (for discovery and the logger).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SpecInfo {
    /// Service name without namespace.
    pub name: String,
    /// Pinned type name.
    pub type_name: &'static str,
    /// Subscriber queue length.
    pub buffer: usize,
    /// History for late subscribers.
    pub history: usize,
    /// Publishers allowed.
    pub max_publishers: usize,
    /// Delivery.
    pub delivery: Delivery,
}

impl<M: Message> From<&ServiceSpec<M>> for SpecInfo {
    fn from(s: &ServiceSpec<M>) -> Self {
        SpecInfo {
            name: s.name.clone(),
            type_name: M::TYPE_NAME,
            buffer: s.buffer,
            history: s.history,
            max_publishers: s.max_publishers,
            delivery: s.delivery,
        }
    }
}

/// Every service a run can have, with its definition.
pub fn all() -> Vec<SpecInfo> {
    let mut v: Vec<SpecInfo> = vec![
        (&imu()).into(),
        (&dvl()).into(),
        (&depth()).into(),
        (&gps()).into(),
        (&ahrs()).into(),
        (&propeller()).into(),
        (&modem()).into(),
        (&lbl_reply()).into(),
        (&lbl_interrogate()).into(),
        (&truth()).into(),
        (&attitude_estimate()).into(),
        (&nav_solution()).into(),
        (&position_fix()).into(),
        (&lbl_solution()).into(),
        (&run_events()).into(),
        (&snapshot::<AttitudeSnapshot>(Role::Attitude)).into(),
        (&snapshot::<AinsSnapshot>(Role::Ains)).into(),
        (&snapshot::<PositioningSnapshot>(Role::Positioning)).into(),
        (&snapshot::<LblSnapshot>(Role::Lbl)).into(),
    ];
    for role in Role::ALL {
        v.push((&health(role)).into());
        v.push((&progress(role)).into());
    }
    v
}

/// The definition of service `name` with message type `M`.
pub fn by_name<M: Message>(name: &str) -> anyhow::Result<ServiceSpec<M>> {
    let info = all()
        .into_iter()
        .find(|s| s.name == name)
        .ok_or_else(|| anyhow::anyhow!("unknown service {name:?}"))?;
    anyhow::ensure!(
        info.type_name == M::TYPE_NAME,
        "service {name} carries {}, not {}",
        info.type_name,
        M::TYPE_NAME
    );
    Ok(ServiceSpec {
        name: info.name,
        buffer: info.buffer,
        history: info.history,
        max_publishers: info.max_publishers,
        delivery: info.delivery,
        _m: PhantomData,
    })
}
