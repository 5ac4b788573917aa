//! `nauta bench smooth`: paper 004's smoother (`nauta smooth`) on a 2-hour
//! LBL mission (issue 15: the forward and backward passes together under
//! 1 s in a release build; reading and writing the files timed apart).
//!
//! The recording is what `nauta launch launch/lbl.toml --set
//! sensor.params.laps=5 --record` writes, made in process so that the bench
//! needs no pipeline: the shipped manifest with five laps of the box
//! (9.5 km, about 2.2 hours), its simulated sensors (every channel: truth,
//! IMU, AHRS, depth, GPS, propeller, LBL replies) in lock step with its LBL
//! filter (which interrogates the transponders and publishes `lbl/nav` and
//! `lbl/interrogate`), and the manifest in `nauta.run`. It is generated
//! once; then `nauta_tools::smooth::smooth_recording` (the command's own
//! code: the recorded manifest's filter) smooths it [`ROUNDS`] times and the
//! median of each part is reported. See BENCHMARKS.md, "LBL smoother".

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::Context as _;
use nauta_log::{LogWriter, WriterOptions};
use nauta_messages::{
    Header, LBL_INTERROGATE_SERVICE, LBL_SOLUTION_SERVICE, LblInterrogation, LblSolution, Role,
    codec,
};
use nauta_runtime::Manifest;
use nauta_sim::lbl_inputs::LblLoop;
use nauta_sim::mission::Origin;
use nauta_sim::params::SensorParams;
use nauta_sim::scenario::Generator;
use nauta_tools::smooth::filter::{ManifestSource, lbl_filter, lbl_process, manifest};
use nauta_tools::smooth::{SmoothSummary, smooth_recording};
use serde::Serialize;
use serde_json::json;

/// Smoothing rounds over the one recording; the median is reported.
pub const ROUNDS: usize = 3;

/// The shipped LBL manifest: the bench runs what a vehicle runs.
const LBL_MANIFEST: &str = include_str!("../../../launch/lbl.toml");

/// Laps of the box for a mission over two hours.
pub const LAPS: u32 = 5;

/// What smoothing the 2-hour mission took.
#[derive(Debug, Clone, Serialize)]
pub struct Smooth2h {
    /// The mission's length, s of simulated time.
    pub mission_s: f64,
    /// The recording's size, bytes.
    pub file_bytes: u64,
    /// Messages in the recording.
    pub messages: u64,
    /// The filter's inputs read from it.
    pub inputs: usize,
    /// Steps of the forward pass (10 Hz).
    pub steps: usize,
    /// `smoother/lbl/nav` messages written.
    pub smoothed: usize,
    /// Median over [`ROUNDS`]: the forward and backward passes together, s
    /// (issue 15's `smooth_2h_s`).
    pub smooth_2h_s: f64,
    /// Median forward pass (the filter over the recorded inputs), s.
    pub forward_s: f64,
    /// Median backward pass (eqs. 7-9), s.
    pub backward_s: f64,
    /// Median read of the recording's inputs, s.
    pub read_s: f64,
    /// Median copy of the recording with the track, s.
    pub write_s: f64,
}

/// The shipped manifest with `laps` laps, parsed.
pub fn lbl_manifest(laps: u32) -> anyhow::Result<(Manifest, String)> {
    let mut table: toml::Table =
        toml::from_str(LBL_MANIFEST).context("launch/lbl.toml does not parse")?;
    nauta_runtime::manifest::apply_override(&mut table, &format!("sensor.params.laps={laps}"))?;
    let text = toml::to_string(&table)?;
    let m = Manifest::parse(Path::new("launch/lbl.toml"), &text)?;
    Ok((m, text))
}

/// Writes the recording of `manifest` (its sensor in lock step with its LBL
/// filter) to `path`; returns (mission s, messages).
pub fn record_lbl_mission(
    manifest: &Manifest,
    text: &str,
    path: &Path,
) -> anyhow::Result<(f64, u64)> {
    let place = "launch/lbl.toml: process.sensor.params";
    let mut sensor = SensorParams::from_table(manifest.params("sensor", None)?, place)?;
    let site = manifest
        .site
        .clone()
        .context("launch/lbl.toml has no [site]")?;
    // The site's transponders are the simulator's, as in `nauta-sensor`.
    sensor.sensors.lbl.transponders = site.transponders.clone();
    let mut g = Generator::new(
        &sensor.scenario,
        Origin::from_degrees(site.latitude_deg, site.longitude_deg),
        sensor.sensors,
        manifest.run.seed,
        manifest.run.duration_s,
    )?;
    let process = lbl_process(manifest, None)?;
    let mut filter = lbl_filter(manifest, &process)?;

    let mut w = LogWriter::create(path, WriterOptions::default())?;
    w.metadata(
        nauta_log::META_RUN,
        BTreeMap::from([
            ("manifest".to_owned(), text.to_owned()),
            ("seed".to_owned(), manifest.run.seed.to_string()),
        ]),
    )?;
    let mut lp = LblLoop::new(sensor.lbl_sync_hz);
    let mut scratch = Vec::new();
    let mut seq = [0u64; 9];
    let (mut nav_seq, mut ping_seq, mut messages) = (0u64, 0u64, 0u64);
    let mut channels = BTreeMap::new();
    let mut end_s = 0.0;
    while let Some((m, step)) = lp.step(&mut g, &mut filter) {
        // The logger stamps the receive time: here the stamp, 1 µs apart.
        let log_time = |stamp: u64, n: u64| 1_700_000_000_000_000_000 + stamp + n * 1_000;
        scratch.clear();
        nauta_sim::wire::to_wire(&m, &mut scratch);
        for mut msg in scratch.drain(..) {
            let k = msg.order();
            msg.header_mut().seq = seq[k];
            seq[k] += 1;
            let ch = match channels.get(&k) {
                Some(ch) => *ch,
                None => {
                    let ch = w.channel(msg.service(), &msg.type_info())?;
                    channels.insert(k, ch);
                    ch
                }
            };
            w.write(ch, log_time(msg.header().stamp_ns, 0), &msg.encode()?)?;
            messages += 1;
        }
        for o in &step.outputs {
            match o {
                nauta_estimation::lbl::LblOutput::Nav(n) => {
                    let mut s = LblSolution::from(n);
                    s.header = Header {
                        flags: s.header.flags,
                        ..Header::new(n.stamp_ns, nav_seq, Role::Lbl, 0)
                    };
                    nav_seq += 1;
                    let data = codec::encode(&s)?;
                    let ch = w.channel(
                        LBL_SOLUTION_SERVICE,
                        &nauta_messages::TypeInfo::of::<LblSolution>(),
                    )?;
                    w.write(ch, log_time(n.stamp_ns, 1), &data)?;
                }
                nauta_estimation::lbl::LblOutput::Ping(p) => {
                    let mut i = LblInterrogation::from(p);
                    i.header.seq = ping_seq;
                    ping_seq += 1;
                    let data = codec::encode(&i)?;
                    let ch = w.channel(
                        LBL_INTERROGATE_SERVICE,
                        &nauta_messages::TypeInfo::of::<LblInterrogation>(),
                    )?;
                    w.write(ch, log_time(p.stamp_ns, 1), &data)?;
                }
            }
            messages += 1;
        }
        end_s = m.stamp_ns as f64 * 1e-9;
    }
    w.finish()?;
    Ok((end_s, messages))
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// A directory of the bench's own, removed when dropped.
struct TempDir(PathBuf);

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Records the 2-hour mission and smooths it [`ROUNDS`] times (issue 15's
/// `smooth_2h_s`; `nauta bench lbl` reports it too).
pub fn smooth_2h() -> anyhow::Result<Smooth2h> {
    let dir =
        TempDir(std::env::temp_dir().join(format!("nauta-bench-smooth-{}", std::process::id())));
    std::fs::create_dir_all(&dir.0)
        .with_context(|| format!("cannot create {}", dir.0.display()))?;
    let input = dir.0.join("lbl-2h.mcap");
    let output = dir.0.join("lbl-2h-smoothed.mcap");
    let (m, text) = lbl_manifest(LAPS)?;
    let (mission_s, messages) = record_lbl_mission(&m, &text, &input)?;
    let mut runs: Vec<SmoothSummary> = Vec::with_capacity(ROUNDS);
    for _ in 0..ROUNDS {
        runs.push(smooth_recording(
            &input,
            &output,
            |recording| {
                let m = manifest(ManifestSource::Recorded, recording, &input, &[])?;
                lbl_filter(&m, &lbl_process(&m, None)?)
            },
            |_, _| {},
        )?);
    }
    let last = runs.last().context("no round")?;
    let of = |f: fn(&SmoothSummary) -> f64| median(runs.iter().map(f).collect());
    Ok(Smooth2h {
        mission_s,
        file_bytes: std::fs::metadata(&input)?.len(),
        messages,
        inputs: last.inputs,
        steps: last.steps,
        smoothed: last.smoothed,
        smooth_2h_s: of(|s| s.forward_s + s.backward_s),
        forward_s: of(|s| s.forward_s),
        backward_s: of(|s| s.backward_s),
        read_s: of(|s| s.read_s),
        write_s: of(|s| s.write_s),
    })
}

/// Runs `nauta bench smooth`.
pub fn run(json_out: bool) -> anyhow::Result<()> {
    let r = smooth_2h()?;
    if json_out {
        println!("{}", json!(r));
        return Ok(());
    }
    println!(
        "LBL smoother on a {:.0} s mission ({} laps of launch/lbl.toml): {} messages, {:.1} MB; {} inputs, {} steps, {} smoothed solutions",
        r.mission_s,
        LAPS,
        r.messages,
        r.file_bytes as f64 / 1e6,
        r.inputs,
        r.steps,
        r.smoothed
    );
    println!("median of {ROUNDS} rounds:");
    println!(
        "  passes (forward + backward)  {:.3} s   (issue 15: < 1 s)",
        r.smooth_2h_s
    );
    println!("    forward                    {:.3} s", r.forward_s);
    println!("    backward                   {:.3} s", r.backward_s);
    println!("  read the recording           {:.3} s", r.read_s);
    println!("  write the smoothed copy      {:.3} s", r.write_s);
    Ok(())
}
