//! `nauta import csv DIR -o OUT.mcap [--manifest M.toml]`: any vehicle's log,
//! one CSV file per channel, as a recording that `nauta replay OUT.mcap
//! --fast --record RUN.mcap` runs the estimators on and `nauta eval RUN.mcap`
//! scores (against `truth.csv`, or the GPS fixes without one).
//!
//! `DIR` holds `site.toml` ([`site`]: origin, declination, sound speed,
//! transponders) and any of `imu.csv`, `dvl.csv`, `ahrs.csv`, `depth.csv`,
//! `gps.csv`, `modem.csv`, `lbl.csv`, `propeller.csv`, `truth.csv`
//! ([`channels`] lists each one's columns, [`table`] the file format; the
//! README has the table). Another `.csv` file in `DIR` is refused (a
//! misspelt channel would otherwise vanish). Times are seconds on one clock
//! for every file; the stamps are the times less the earliest time of the
//! log, plus 1 s (`nauta.import` records that time as `time_origin_s`).
//!
//! The recording carries a manifest (`--manifest` gives one instead, whose
//! `[site]`, if any, must agree with `site.toml`) that replays the channels
//! and runs what they allow among nauta's services ([`plan`]): the attitude
//! when the IMU has a magnetometer (its alignment needs one), the aided INS
//! when there is something to navigate with.

pub mod channels;
pub mod site;
pub mod table;

#[cfg(test)]
mod tests;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context as _, bail};
use nauta_log::{LogWriter, WriterOptions};
use nauta_messages::SensorMessage;

pub use site::CsvSite;
use table::Table;

/// Arguments of `nauta import csv`.
#[derive(Debug, clap::Args)]
pub struct ImportCsvArgs {
    /// The directory: `site.toml` and one CSV file per channel (see the README).
    pub dir: PathBuf,
    /// The recording to write (MCAP).
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
    /// Store this manifest in the recording instead of the one the import
    /// writes (it must have a `nauta-sensor` process, which replays the
    /// recording).
    #[arg(long)]
    pub manifest: Option<PathBuf>,
}

/// A channel file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Channel {
    /// `truth.csv` → `sim/truth`.
    Truth,
    /// `imu.csv` → `sensor/imu`.
    Imu,
    /// `ahrs.csv` → `sensor/ahrs`.
    Ahrs,
    /// `dvl.csv` → `sensor/dvl`.
    Dvl,
    /// `depth.csv` → `sensor/depth`.
    Depth,
    /// `gps.csv` → `sensor/gps`.
    Gps,
    /// `propeller.csv` → `sensor/propeller`.
    Propeller,
    /// `modem.csv` → `sensor/modem`.
    Modem,
    /// `lbl.csv` → `sensor/lbl`.
    Lbl,
}

impl Channel {
    /// Every channel, in the sensor's publishing order within a stamp
    /// ([`SensorMessage::SERVICES`]).
    pub const ALL: [Channel; 9] = [
        Channel::Truth,
        Channel::Imu,
        Channel::Ahrs,
        Channel::Dvl,
        Channel::Depth,
        Channel::Gps,
        Channel::Propeller,
        Channel::Modem,
        Channel::Lbl,
    ];

    /// Its file name.
    pub fn file(self) -> &'static str {
        match self {
            Channel::Truth => "truth.csv",
            Channel::Imu => "imu.csv",
            Channel::Ahrs => "ahrs.csv",
            Channel::Dvl => "dvl.csv",
            Channel::Depth => "depth.csv",
            Channel::Gps => "gps.csv",
            Channel::Propeller => "propeller.csv",
            Channel::Modem => "modem.csv",
            Channel::Lbl => "lbl.csv",
        }
    }

    /// Its columns.
    pub fn spec(self) -> &'static [table::Col] {
        match self {
            Channel::Truth => channels::TRUTH,
            Channel::Imu => channels::IMU,
            Channel::Ahrs => channels::AHRS,
            Channel::Dvl => channels::DVL,
            Channel::Depth => channels::DEPTH,
            Channel::Gps => channels::GPS,
            Channel::Propeller => channels::PROPELLER,
            Channel::Modem => channels::MODEM,
            Channel::Lbl => channels::LBL,
        }
    }
}

/// A log read from its directory and turned into messages.
#[derive(Debug, Clone)]
pub struct CsvLog {
    /// The site.
    pub site: CsvSite,
    /// Each channel's messages, in stamp order.
    pub channels: BTreeMap<Channel, Vec<SensorMessage>>,
    /// The earliest time of the log, s (stamp 1 s).
    pub time_origin_s: f64,
    /// True when `imu.csv` has the magnetometer columns.
    pub imu_magnetometer: bool,
}

impl CsvLog {
    /// Messages of `c` (none if the log has no such file).
    pub fn messages(&self, c: Channel) -> &[SensorMessage] {
        self.channels.get(&c).map_or(&[], Vec::as_slice)
    }

    /// True when the log has channel `c`.
    pub fn has(&self, c: Channel) -> bool {
        !self.messages(c).is_empty()
    }

    /// The last stamp, ns.
    pub fn last_stamp_ns(&self) -> u64 {
        self.channels
            .values()
            .filter_map(|m| m.last().map(|m| m.header().stamp_ns))
            .max()
            .unwrap_or(0)
    }
}

/// Reads `dir`: `site.toml` and the channel files.
pub fn read(dir: &Path) -> anyhow::Result<CsvLog> {
    let entries =
        std::fs::read_dir(dir).with_context(|| format!("cannot read {}", dir.display()))?;
    let mut found = Vec::new();
    for e in entries {
        let p = e
            .with_context(|| format!("cannot read {}", dir.display()))?
            .path();
        let Some(name) = p.file_name().and_then(|n| n.to_str()) else {
            continue;
        };
        if !name.to_ascii_lowercase().ends_with(".csv") {
            continue;
        }
        match Channel::ALL.iter().find(|c| c.file() == name) {
            Some(c) => found.push(*c),
            None => bail!(
                "{}: not a channel file; a channel is one of {}",
                p.display(),
                Channel::ALL.map(Channel::file).join(", ")
            ),
        }
    }
    found.sort();
    if found.is_empty() {
        bail!(
            "{}: no channel file (one of {})",
            dir.display(),
            Channel::ALL.map(Channel::file).join(", ")
        );
    }
    let site = CsvSite::read(&dir.join("site.toml"))?;
    let mut tables = BTreeMap::new();
    for c in &found {
        let t = Table::read(&dir.join(c.file()), c.spec())?;
        anyhow::ensure!(!t.is_empty(), "{}: no data rows after the header", t.path);
        tables.insert(*c, t);
    }
    let lbl_rows = match tables.get(&Channel::Lbl) {
        Some(t) => channels::lbl_rows(t, &site)?,
        None => Vec::new(),
    };
    let time_origin_s = tables
        .values()
        .flat_map(channels::times)
        .chain(lbl_rows.iter().map(|r| r.ping_s))
        .reduce(f64::min)
        .with_context(|| format!("{}: the channel files have no rows", dir.display()))?;
    let clock = channels::Clock {
        t0_s: time_origin_s,
    };
    let imu_magnetometer = tables
        .get(&Channel::Imu)
        .is_some_and(channels::imu_has_magnetometer);
    let mut out = BTreeMap::new();
    for (c, t) in &tables {
        let messages = match c {
            Channel::Truth => channels::truth(t, &clock)?,
            Channel::Imu => channels::imu(t, &clock)?,
            Channel::Ahrs => channels::ahrs(t, &clock)?,
            Channel::Dvl => channels::dvl(t, &clock)?,
            Channel::Depth => channels::depth(t, &clock)?,
            Channel::Gps => channels::gps(t, &clock)?,
            Channel::Propeller => channels::propeller(t, &clock)?,
            Channel::Modem => channels::modem(t, &clock, &site)?,
            Channel::Lbl => channels::lbl(t, &lbl_rows, &clock)?,
        };
        out.insert(*c, messages);
    }
    Ok(CsvLog {
        site,
        channels: out,
        time_origin_s,
        imu_magnetometer,
    })
}

/// What the written manifest runs, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    /// Run the attitude process (`pf`).
    pub attitude: bool,
    /// The aided INS's variant, if it runs.
    pub ains: Option<&'static str>,
    /// One line per choice, for the manifest's comments.
    pub notes: Vec<String>,
}

/// What the channels allow among nauta's services:
/// - the attitude when `imu.csv` has the magnetometer (its alignment takes
///   roll, pitch and the magnetic heading from still samples);
/// - the aided INS `ekf` on an IMU with a heading (the attitude's, or the
///   AHRS's), else `dr` (paper 002) on the AHRS and the DVL; nothing when
///   neither is possible.
pub fn plan(log: &CsvLog) -> Plan {
    let mut notes = Vec::new();
    let imu = log.has(Channel::Imu);
    let attitude = imu && log.imu_magnetometer;
    if imu && !attitude {
        notes.push(
            "no attitude process: imu.csv has no magnetometer (mag_*_ut), which its alignment needs"
                .to_owned(),
        );
    }
    let heading = attitude || log.has(Channel::Ahrs);
    let ains = if imu && heading {
        notes.push(format!(
            "ains ekf: the IMU with the {} heading{}",
            if attitude { "attitude's" } else { "AHRS's" },
            if log.has(Channel::Dvl) {
                ", aided by the DVL"
            } else {
                ""
            }
        ));
        Some("ekf")
    } else if log.has(Channel::Dvl) && log.has(Channel::Ahrs) {
        notes.push("ains dr (paper 002): the DVL's velocity rotated by the AHRS".to_owned());
        Some("dr")
    } else {
        notes.push(
            "no ains: it needs an IMU with a heading (magnetometer or ahrs.csv), or dvl.csv with ahrs.csv"
                .to_owned(),
        );
        None
    };
    Plan {
        attitude,
        ains,
        notes,
    }
}

/// The median interval of `m`'s stamps, s (none for fewer than 2).
fn median_period_s(m: &[SensorMessage]) -> Option<f64> {
    let mut d: Vec<u64> = m
        .windows(2)
        .map(|w| w[1].header().stamp_ns - w[0].header().stamp_ns)
        .collect();
    if d.is_empty() {
        return None;
    }
    let mid = d.len() / 2;
    let (_, x, _) = d.select_nth_unstable(mid);
    Some(*x as f64 * 1e-9)
}

/// The manifest the import writes.
pub fn manifest(log: &CsvLog, dir: &Path, duration_s: f64) -> String {
    let p = plan(log);
    let s = &log.site;
    let mut m = format!(
        r#"# {dir}, imported by `nauta import csv`: replay it with
# `nauta replay FILE --fast --record RUN.mcap`, then `nauta eval RUN.mcap`.
"#,
        dir = std::path::absolute(dir)
            .unwrap_or_else(|_| dir.to_path_buf())
            .display()
    );
    for n in &p.notes {
        m += &format!("# {n}\n");
    }
    if log.has(Channel::Modem) {
        m += "# sensor/modem (the buoy's position and time of flight) is for paper 000's\n\
              # acoustic positioning (positioning/fix), a service nauta does not have yet.\n";
    }
    if log.has(Channel::Lbl) {
        m += "# sensor/lbl (transponder round trips) is for the LBL navigator (papers\n\
              # 003/004), a service nauta does not have yet.\n";
    }
    m += &format!(
        r#"[run]
clock = "sim"
duration_s = {duration_s:.1}
seed = 0

[site]
latitude_deg = {lat:?}
longitude_deg = {lon:?}
magnetic_declination_deg = {dec:?}

[process.sensor]
bin = "nauta-sensor"   # on replay, it republishes this recording (--from)
"#,
        lat = s.latitude_deg,
        lon = s.longitude_deg,
        dec = s.magnetic_declination_deg,
    );
    if s.sound_speed_m_s.is_some() || !s.transponders.is_empty() {
        // The manifest has no place for them (`[site]` and the sensor's
        // parameters refuse unknown keys): the import's `nauta.run` holds them.
        m += &format!(
            "# site.toml's acoustics (sound speed, {} transponders) are in this recording's\n\
             # nauta.run metadata (`site`), not in the replay's.\n",
            s.transponders.len()
        );
    }
    if p.attitude {
        m += r#"
[process.attitude]
bin = "nauta-attitude"
variant = "pf"
# Alignment over the first 400 IMU samples: the log must start at rest
# (--set attitude.variants.pf.alignment_samples=N otherwise).
variants.pf = { alignment_samples = 400 }
variants.gyro = { alignment_samples = 400 }
variants.mekf = { alignment_samples = 400 }
"#;
    }
    if let Some(variant) = p.ains {
        // An aiding stream counts as present for `aiding_timeout_s`: 2.5
        // periods of the slowest of the DVL and the AHRS, when that is longer
        // than the variants' defaults (1 s; 1.5 s for ekf).
        let slowest = [Channel::Dvl, Channel::Ahrs]
            .iter()
            .filter_map(|c| median_period_s(log.messages(*c)))
            .reduce(f64::max);
        let timeout = slowest.map(|t| 2.5 * t).filter(|t| *t > 1.0);
        let table = match timeout {
            Some(t) => format!("{{ aiding_timeout_s = {:.2} }}", t.max(1.5)),
            None => "{}".to_owned(),
        };
        m += &format!(
            r#"
[process.ains]
bin = "nauta-ains"
variant = "{variant}"   # --set ains.variant=pf|dr|ekf
"#
        );
        if let Some(t) = slowest.filter(|_| timeout.is_some()) {
            m += &format!("# The DVL or the AHRS comes every {t:.3} s (median).\n");
        }
        for v in ["dr", "ekf", "pf"] {
            m += &format!("variants.{v} = {table}\n");
        }
    }
    m
}

/// Refuses a `--manifest` that cannot be replayed or whose site disagrees
/// with `site.toml`; returns its text.
fn given_manifest(path: &Path, site: &CsvSite, duration_s: f64) -> anyhow::Result<String> {
    let m = nauta_runtime::Manifest::load(path)?;
    if !m
        .processes
        .values()
        .any(|p| Path::new(&p.bin).file_name() == Some(std::ffi::OsStr::new("nauta-sensor")))
    {
        bail!(
            "{}: no nauta-sensor process: nauta replay republishes the recording through it",
            path.display()
        );
    }
    if let Some(s) = &m.site {
        for (key, a, b) in [
            ("latitude_deg", s.latitude_deg, site.latitude_deg),
            ("longitude_deg", s.longitude_deg, site.longitude_deg),
            (
                "magnetic_declination_deg",
                s.magnetic_declination_deg,
                site.magnetic_declination_deg,
            ),
        ] {
            if a != b {
                bail!(
                    "{}: [site] {key} = {a} differs from site.toml's {b}",
                    path.display()
                );
            }
        }
    }
    if m.run.duration_s < duration_s - 2.0 {
        eprintln!(
            "nauta: note: {}: run.duration_s = {} s is shorter than the log ({:.1} s); a replay stops there",
            path.display(),
            m.run.duration_s,
            duration_s - 2.0
        );
    }
    std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))
}

/// Writes `log` to `out` with `manifest_text`; returns the number of messages.
pub fn write(
    log: &CsvLog,
    source: &Path,
    out: &Path,
    manifest_text: &str,
    manifest_source: &str,
) -> anyhow::Result<u64> {
    let mut w = LogWriter::create(out, WriterOptions::default())?;
    let s = &log.site;
    let mut run = BTreeMap::new();
    run.insert("manifest".to_owned(), manifest_text.to_owned());
    run.insert("seed".to_owned(), "0".to_owned());
    run.insert("clock".to_owned(), "sim".to_owned());
    run.insert(
        "command_line".to_owned(),
        std::env::args().collect::<Vec<_>>().join(" "),
    );
    run.insert("origin_lat_deg".to_owned(), s.latitude_deg.to_string());
    run.insert("origin_lon_deg".to_owned(), s.longitude_deg.to_string());
    run.insert(
        "magnetic_declination_deg".to_owned(),
        s.magnetic_declination_deg.to_string(),
    );
    if let Some(c) = s.sound_speed_m_s {
        run.insert("sound_speed_m_s".to_owned(), c.to_string());
    }
    if let Some(t) = s.turnaround_s {
        run.insert("turnaround".to_owned(), t.to_string());
    }
    run.insert("site".to_owned(), s.to_toml());
    w.metadata(nauta_log::META_RUN, run)?;
    let mut import = BTreeMap::new();
    let source = std::path::absolute(source).unwrap_or_else(|_| source.to_path_buf());
    import.insert("source".to_owned(), source.display().to_string());
    import.insert("format".to_owned(), "nauta import csv".to_owned());
    import.insert("time_origin_s".to_owned(), log.time_origin_s.to_string());
    import.insert("manifest".to_owned(), manifest_source.to_owned());
    for (c, m) in &log.channels {
        import.insert(format!("rows.{}", c.file()), m.len().to_string());
    }
    w.metadata("nauta.import", import)?;

    // Every channel is in stamp order: merge them, ties in the sensor's
    // publishing order (the truth first), as `nauta-sensor --from` sorts.
    let mut heads: Vec<(&[SensorMessage], usize)> =
        log.channels.values().map(|m| (m.as_slice(), 0)).collect();
    let mut n = 0u64;
    loop {
        let next = heads
            .iter()
            .enumerate()
            .filter_map(|(i, (m, k))| m.get(*k).map(|x| ((x.header().stamp_ns, x.order()), i)))
            .min();
        let Some((_, i)) = next else { break };
        let (m, k) = &mut heads[i];
        write_one(&mut w, &m[*k])?;
        *k += 1;
        n += 1;
    }
    w.finish()?;
    Ok(n)
}

fn write_one(w: &mut LogWriter, m: &SensorMessage) -> anyhow::Result<()> {
    use nauta_messages::*;
    let s = m.header().stamp_ns;
    match m {
        SensorMessage::Truth(x) => w.write_message(TRUTH_SERVICE, s, x),
        SensorMessage::Imu(x) => w.write_message(IMU_SERVICE, s, x),
        SensorMessage::Ahrs(x) => w.write_message(AHRS_SERVICE, s, x),
        SensorMessage::Dvl(x) => w.write_message(DVL_SERVICE, s, x),
        SensorMessage::Depth(x) => w.write_message(DEPTH_SERVICE, s, x),
        SensorMessage::Gps(x) => w.write_message(GPS_SERVICE, s, x),
        SensorMessage::Propeller(x) => w.write_message(PROPELLER_SERVICE, s, x),
        SensorMessage::Modem(x) => w.write_message(MODEM_SERVICE, s, x),
        SensorMessage::Lbl(x) => w.write_message(LBL_REPLY_SERVICE, s, x),
    }
}

/// `nauta import csv`.
pub fn csv(args: &ImportCsvArgs) -> anyhow::Result<ExitCode> {
    let log = read(&args.dir)?;
    // The stamps start at 1 s; one more second after the last.
    let duration_s = (log.last_stamp_ns() as f64 * 1e-9 + 1.0).ceil();
    let (text, source) = match &args.manifest {
        Some(m) => (
            given_manifest(m, &log.site, duration_s)?,
            m.display().to_string(),
        ),
        None => (manifest(&log, &args.dir, duration_s), "written".to_owned()),
    };
    let n = match write(&log, &args.dir, &args.output, &text, &source) {
        Ok(n) => n,
        Err(e) => {
            let _ = std::fs::remove_file(&args.output);
            return Err(e);
        }
    };
    let counts: Vec<String> = log
        .channels
        .iter()
        .map(|(c, m)| format!("{} {}", m.len(), c.file().trim_end_matches(".csv")))
        .collect();
    eprintln!(
        "nauta: {}: {n} messages over {:.1} s ({}) -> {}",
        args.dir.display(),
        (log.last_stamp_ns() as f64 * 1e-9 - 1.0).max(0.0),
        counts.join(", "),
        args.output.display()
    );
    if args.manifest.is_none() {
        for note in plan(&log).notes {
            eprintln!("nauta: {note}");
        }
    }
    Ok(ExitCode::SUCCESS)
}
