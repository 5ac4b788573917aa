//! The launcher's view of a run: a tap on every output service the processes
//! describe (through the message registry, as the logger does), message counts,
//! rates and sequence gaps, and what the run summary reports of the estimates:
//! `nauta eval`'s errors and a digest per estimate stream.

use std::any::Any;
use std::collections::BTreeMap;
use std::path::Path;
use std::time::{Duration, Instant};

use nauta_messages::registry::{MessageVisitor, visit_by_name};
use nauta_messages::*;
use nauta_runtime::ports::Inbox;
use nauta_runtime::{Connect, Context, Manifest, Subscriber, services};

use nauta_tools::eval::{self, Data, Evaluation, data::StreamKind};

/// A type-erased subscriber.
pub trait Tap: std::fmt::Debug {
    /// Service name.
    fn service(&self) -> &str;
    /// Receives everything available, passing each message to `obs`.
    fn drain(&mut self, obs: &mut Observer) -> anyhow::Result<usize>;
    /// Messages received.
    fn count(&self) -> u64;
    /// Sequence gaps seen.
    fn gaps(&self) -> u64;
    /// First and last stamps seen, ns.
    fn span(&self) -> Option<(u64, u64)>;
    /// Wall time from receiving the first message to receiving the last.
    fn wall_span(&self) -> Option<Duration>;
    /// The latest message's stamp and bincode encoding, kept for snapshot
    /// services only (the launcher hands it to a restarted process).
    fn latest(&self) -> Option<&(u64, Vec<u8>)>;
    /// Attaches to the publishers present now; false while there is none.
    fn connect(&self) -> anyhow::Result<bool>;
}

// By hand: the subscriber is an iceoryx2 port.
impl<M: Message> std::fmt::Debug for TypedTap<M> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TypedTap")
            .field("type", &M::TYPE_NAME)
            .field("span", &self.span)
            .finish_non_exhaustive()
    }
}

struct TypedTap<M: Message> {
    sub: Subscriber<M>,
    span: Option<(u64, u64)>,
    received: Option<(Instant, Instant)>,
    keep_latest: bool,
    latest: Option<(u64, Vec<u8>)>,
}

impl<M: Message> Tap for TypedTap<M> {
    fn service(&self) -> &str {
        self.sub.service()
    }
    fn drain(&mut self, obs: &mut Observer) -> anyhow::Result<usize> {
        let mut n = 0;
        let now = Instant::now();
        while let Some(m) = self.sub.receive()? {
            self.received = Some(self.received.map_or((now, now), |(a, _)| (a, now)));
            let s = m.header().stamp_ns;
            self.span = Some(self.span.map_or((s, s), |(a, b)| (a.min(s), b.max(s))));
            if self.keep_latest {
                match nauta_messages::codec::encode(&m) {
                    Ok(bytes) => self.latest = Some((s, bytes)),
                    Err(e) => {
                        tracing::warn!(service = %self.sub.service(), error = %e, "snapshot not kept")
                    }
                }
            }
            obs.observe(self.sub.service(), &m);
            n += 1;
        }
        Ok(n)
    }
    fn count(&self) -> u64 {
        self.sub.received()
    }
    fn gaps(&self) -> u64 {
        self.sub.gaps().missing
    }
    fn span(&self) -> Option<(u64, u64)> {
        self.span
    }
    fn wall_span(&self) -> Option<Duration> {
        self.received.map(|(a, b)| b - a)
    }
    fn latest(&self) -> Option<&(u64, Vec<u8>)> {
        self.latest.as_ref()
    }
    fn connect(&self) -> anyhow::Result<bool> {
        Connect::connect(&self.sub)
    }
}

struct MakeTap<'a> {
    ctx: &'a Context,
    service: &'a str,
    out: Option<anyhow::Result<(Box<dyn Tap>, Inbox)>>,
}

impl MessageVisitor for MakeTap<'_> {
    fn visit<M: Message>(&mut self) {
        let made = services::by_name::<M>(self.service).and_then(|spec| {
            let (sub, inbox) = self.ctx.subscriber(&spec)?;
            Ok((
                Box::new(TypedTap {
                    sub,
                    span: None,
                    received: None,
                    keep_latest: self.service.ends_with("/snapshot"),
                    latest: None,
                }) as Box<dyn Tap>,
                inbox,
            ))
        });
        self.out = Some(made);
    }
}

/// Opens a tap on `service` carrying `type_name`.
pub fn tap(ctx: &Context, service: &str, type_name: &str) -> anyhow::Result<(Box<dyn Tap>, Inbox)> {
    let mut v = MakeTap {
        ctx,
        service,
        out: None,
    };
    if !visit_by_name(type_name, &mut v) {
        anyhow::bail!("service {service} has unknown type {type_name}");
    }
    v.out
        .unwrap_or_else(|| anyhow::bail!("no tap made for {service}"))
}

/// What the launcher learns from the messages its taps receive: the truth and
/// every estimate stream, kept as `nauta eval` reads them from a recording (so
/// the summary's errors are eval's), a digest of each estimate stream, and
/// each process's latest health.
#[derive(Debug, Default)]
pub struct Observer {
    /// The truth and the estimate streams, checked as eval checks them.
    data: Data,
    /// FNV-1a (64 bit) of the encoding of every message of each estimate
    /// stream, in the order received.
    digests: BTreeMap<String, u64>,
    /// The latest (dropped, rejected) of each (health service, instance).
    health: BTreeMap<(String, u32), (u64, u64)>,
    /// Per health service: the previous and the latest message, with the
    /// time each arrived (rates for `nauta status`).
    pub latest_health: BTreeMap<String, HealthPair>,
    /// The progress services whose end of stream was seen.
    pub end_of_stream: std::collections::BTreeSet<String>,
}

/// A health message and when it arrived.
pub type TimedHealth = (Instant, Health);
/// The previous (if any) and the latest health message of a process.
pub type HealthPair = (Option<TimedHealth>, TimedHealth);

/// FNV-1a's offset basis (64 bit).
const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
/// FNV-1a's prime (64 bit).
const FNV_PRIME: u64 = 0x0100_0000_01b3;

impl Observer {
    fn observe<M: Message>(&mut self, service: &str, msg: &M) {
        let estimate = StreamKind::of(M::TYPE_NAME).is_some();
        if estimate || service == TRUTH_SERVICE {
            match codec::encode(msg) {
                Ok(bytes) => {
                    if estimate {
                        let d = self.digests.entry(service.to_owned()).or_insert(FNV_OFFSET);
                        for b in &bytes {
                            *d = (*d ^ u64::from(*b)).wrapping_mul(FNV_PRIME);
                        }
                    }
                    self.data.take(service, M::TYPE_NAME, &bytes);
                }
                Err(e) => tracing::warn!(%service, error = %e, "message not evaluated"),
            }
        } else if let Some(h) = (msg as &dyn Any).downcast_ref::<Health>() {
            self.health.insert(
                (service.to_owned(), h.header.instance),
                (h.dropped, h.rejected),
            );
            let now = Instant::now();
            let prev = self.latest_health.remove(service).map(|(_, last)| last);
            self.latest_health
                .insert(service.to_owned(), (prev, (now, *h)));
        } else if let Some(p) = (msg as &dyn Any).downcast_ref::<Progress>()
            && p.header.is_end_of_stream()
        {
            self.end_of_stream.insert(service.to_owned());
        }
    }

    /// `nauta eval`'s evaluation of every estimate stream received, against
    /// the truth received (the local frame of `lbl/nav` from `manifest`'s
    /// site); `None` when the run had no estimate or no truth.
    pub fn evaluate(&mut self, manifest: &Manifest) -> Option<Evaluation> {
        let data = &mut self.data;
        data.run = eval::live::run_info(manifest);
        eval::live::sort(data);
        match eval::evaluate(Path::new("the run"), data) {
            Ok(e) => {
                for (topic, why) in &e.skipped {
                    tracing::warn!(%topic, "not evaluated: {why}");
                }
                Some(e)
            }
            Err(e) => {
                tracing::debug!("no estimate errors: {e:#}");
                None
            }
        }
    }

    /// The digest of each estimate stream (hex), equal for equal outputs.
    pub fn digests(&self) -> BTreeMap<String, String> {
        self.digests
            .iter()
            .map(|(t, d)| (t.clone(), format!("{d:016x}")))
            .collect()
    }

    /// Messages lost and rejected inside the processes: the sum over every
    /// instance (a restarted one counts from zero) of its last health.
    pub fn process_losses(&self) -> (u64, u64) {
        self.health
            .values()
            .fold((0, 0), |(l, r), (dl, dr)| (l + dl, r + dr))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nauta_estimation::earth::{meridian_radius, transverse_radius};

    const DEPTH_M: f64 = 10.0;

    fn survey() -> Manifest {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../launch/survey.toml");
        Manifest::load(&path).expect("launch/survey.toml loads")
    }

    /// 100 truth samples at the survey's origin, at rest, and for each stamp
    /// one message of every estimate type, each off by a known error: yaw
    /// +0.01 rad, `ains/nav` 1 m north, `positioning/fix` 2 m east, `lbl/nav`
    /// 3 m north in the local frame of the manifest's site.
    fn observe_run(obs: &mut Observer, site: &nauta_runtime::manifest::Site, yaw: f64) {
        let (lat, lon) = (
            site.latitude_deg.to_radians(),
            site.longitude_deg.to_radians(),
        );
        let h = -DEPTH_M;
        for i in 1..=100u64 {
            let stamp = i * 10_000_000;
            let header = |role| Header::new(stamp, i - 1, role, 0);
            let truth = TruthState {
                header: header(Role::Sensor),
                lat_rad: lat,
                lon_rad: lon,
                depth_m: DEPTH_M,
                quat_nb: [1.0, 0.0, 0.0, 0.0],
                ..Default::default()
            };
            obs.observe(TRUTH_SERVICE, &truth);
            let att = AttitudeEstimate {
                header: header(Role::Attitude),
                quat_nb: [(yaw / 2.0).cos(), 0.0, 0.0, (yaw / 2.0).sin()],
                ..Default::default()
            };
            obs.observe(ATTITUDE_ESTIMATE_SERVICE, &att);
            let nav = NavSolution {
                header: header(Role::Ains),
                lat_rad: lat + 1.0 / (meridian_radius(lat) + h),
                lon_rad: lon,
                depth_m: DEPTH_M,
                ..Default::default()
            };
            obs.observe(NAV_SOLUTION_SERVICE, &nav);
            let fix = PositionFix {
                header: header(Role::Positioning),
                lat_rad: lat,
                lon_rad: lon + 2.0 / ((transverse_radius(lat) + h) * lat.cos()),
                ..Default::default()
            };
            obs.observe(POSITION_FIX_SERVICE, &fix);
            let lbl = LblSolution {
                header: header(Role::Lbl),
                x_m: 3.0,
                ..Default::default()
            };
            obs.observe(LBL_SOLUTION_SERVICE, &lbl);
        }
    }

    #[test]
    fn every_estimate_stream_is_evaluated_and_digested() {
        let manifest = survey();
        let site = manifest.site.clone().expect("the survey has a site");
        let mut obs = Observer::default();
        observe_run(&mut obs, &site, 0.01);
        let eval = obs.evaluate(&manifest).expect("an evaluation");
        assert!(eval.skipped.is_empty(), "{:?}", eval.skipped);
        let horizontal = |topic: &str| {
            let m = &eval.streams[topic];
            assert_eq!(
                (m.samples, m.unmatched, m.rejected),
                (100, 0, 0),
                "{topic}: {m:?}"
            );
            m.horizontal_rms_m.expect("horizontal error")
        };
        assert!((horizontal(NAV_SOLUTION_SERVICE) - 1.0).abs() < 1e-3);
        assert!((horizontal(POSITION_FIX_SERVICE) - 2.0).abs() < 1e-3);
        assert!((horizontal(LBL_SOLUTION_SERVICE) - 3.0).abs() < 1e-3);
        let att = &eval.streams[ATTITUDE_ESTIMATE_SERVICE];
        assert_eq!(att.samples, 100);
        let yaw = att.yaw_rms_deg.expect("yaw");
        assert!((yaw - 0.01f64.to_degrees()).abs() < 1e-9, "{yaw}");

        // Equal outputs, equal digests; one stream changed, only its digest.
        let digests = obs.digests();
        assert_eq!(digests.len(), 4, "{digests:?}");
        let mut same = Observer::default();
        observe_run(&mut same, &site, 0.01);
        assert_eq!(same.digests(), digests);
        let mut other = Observer::default();
        observe_run(&mut other, &site, 0.02);
        let changed: Vec<&String> = digests
            .keys()
            .filter(|t| other.digests()[*t] != digests[*t])
            .collect();
        assert_eq!(changed, [ATTITUDE_ESTIMATE_SERVICE]);
    }

    #[test]
    fn the_attitude_digest_is_fnv_1a_of_the_encodings() {
        let mut obs = Observer::default();
        let est = AttitudeEstimate {
            header: Header::new(10_000_000, 0, Role::Attitude, 0),
            quat_nb: [1.0, 0.0, 0.0, 0.0],
            ..Default::default()
        };
        obs.observe(ATTITUDE_ESTIMATE_SERVICE, &est);
        obs.observe(ATTITUDE_ESTIMATE_SERVICE, &est);
        // FNV-1a as published (http://www.isthe.com/chongo/tech/comp/fnv/):
        // the empty input hashes to the offset basis, "a" to af63dc4c8601ec8c.
        let fnv = |bytes: &[u8]| {
            bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
                (h ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3)
            })
        };
        assert_eq!(fnv(b"a"), 0xaf63_dc4c_8601_ec8c);
        let bytes = codec::encode(&est).expect("encodes");
        let twice = [bytes.clone(), bytes].concat();
        assert_eq!(
            obs.digests()[ATTITUDE_ESTIMATE_SERVICE],
            format!("{:016x}", fnv(&twice))
        );
    }
}
