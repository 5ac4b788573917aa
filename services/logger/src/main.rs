//! `nauta-logger`: records every service of a run to one MCAP file (DESIGN §8).
//!
//! It discovers the run's publish-subscribe services (and those that appear
//! later), subscribes to each one whose name and type it knows (the service
//! definitions of `nauta_runtime::services` and the message registry), and
//! writes every message with `nauta_log`: chunked, zstd-compressed, flushed at
//! least once per second, with the run's metadata at the start and its own
//! per-channel counts (received, sequence gaps per source and instance) at the
//! end. Started by the launcher from a manifest (after every other process, so
//! that their publishers exist; stopped after them, so that it drains them
//! all) or attached to a running pipeline with `nauta record -o FILE`.

use std::collections::{BTreeMap, BTreeSet};
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use anyhow::Context as _;
use clap::Parser;
use nauta_log::{LogWriter, WriterOptions};
use nauta_runtime::process::{ProcessArgs, init_tracing};
use nauta_runtime::{
    Context, Describe, EventLoop, HealthReporter, LoopExit, Manifest, Namespace, Wake,
};

mod discovery;
mod taps;

use taps::RecordingTap;

/// Records every service of a run to one MCAP file.
#[derive(Debug, Parser)]
#[command(name = "nauta-logger", version, about)]
struct Args {
    #[command(flatten)]
    process: ProcessArgs,
    /// Output file (MCAP). `{run}` is replaced by the run's namespace. A
    /// restarted logger (instance K > 0) writes `NAME.K.mcap` beside it, so the
    /// file of the instance that died is kept as it was.
    #[arg(short = 'o', long = "output", value_name = "FILE")]
    output: Option<PathBuf>,
    /// Stop (and finish the file) once this process has exited: `nauta record`
    /// follows the run's launcher, which outlives every process of the run.
    #[arg(long, value_name = "PID")]
    follow_pid: Option<u32>,
}

/// How often the logger looks for services that appeared.
const DISCOVERY_PERIOD: Duration = Duration::from_millis(250);
/// The file is flushed (current chunk closed and written) at least this often.
const FLUSH_PERIOD: Duration = Duration::from_secs(1);

fn describe() -> Describe {
    Describe {
        role: nauta_messages::Role::Logger.name().into(),
        inputs: Vec::new(),
        outputs: Vec::new(),
        variants: vec!["mcap".into()],
        source: false,
    }
}

fn main() -> ExitCode {
    init_tracing();
    let args = Args::parse();
    let result = if args.process.describe {
        describe().print()
    } else if args.process.check {
        check(&args)
    } else {
        run(&args)
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            if args.process.check {
                eprintln!("{e:#}");
            } else {
                tracing::error!("{e:#}");
            }
            ExitCode::FAILURE
        }
    }
}

/// The output named on the command line or, for `--check` (which the
/// launcher runs without the process's `args`), in the manifest's `args`.
fn output_of(args: &Args) -> Option<PathBuf> {
    if let Some(o) = &args.output {
        return Some(o.clone());
    }
    let manifest = Manifest::load(args.process.manifest.as_deref()?).ok()?;
    let name = args.process.process.as_deref().unwrap_or("logger");
    let section = manifest.processes.get(name)?;
    let mut it = section.args.iter();
    while let Some(a) = it.next() {
        if a == "-o" || a == "--output" {
            return it.next().map(PathBuf::from);
        }
        if let Some(v) = a.strip_prefix("--output=") {
            return Some(PathBuf::from(v));
        }
    }
    None
}

/// `--check`: the output must be named, as an `.mcap` file.
fn check(args: &Args) -> anyhow::Result<()> {
    let out = output_of(args).context(
        "nauta-logger needs -o FILE (in the manifest: args = [\"-o\", \"runs/{run}.mcap\"])",
    )?;
    anyhow::ensure!(
        out.extension().is_some_and(|e| e == "mcap"),
        "the output {} should end in .mcap",
        out.display()
    );
    Ok(())
}

/// The file this instance writes.
fn output_path(template: &Path, namespace: &str, instance: u32) -> PathBuf {
    let path = PathBuf::from(template.to_string_lossy().replace("{run}", namespace));
    if instance == 0 {
        return path;
    }
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!("{stem}.{instance}.mcap"))
}

fn now_ns() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_nanos() as u64)
        .unwrap_or(0)
}

/// The `nauta.run` metadata: how the run was made.
fn run_metadata(
    args: &Args,
    manifest: Option<&Manifest>,
    namespace: &str,
) -> BTreeMap<String, String> {
    let mut m = BTreeMap::new();
    m.insert("namespace".into(), namespace.to_owned());
    m.insert("git_revision".into(), env!("NAUTA_GIT_REVISION").to_owned());
    m.insert(
        "logger_command_line".into(),
        std::env::args().collect::<Vec<_>>().join(" "),
    );
    if let Ok(cmd) = std::env::var("NAUTA_COMMAND_LINE") {
        m.insert("command_line".into(), cmd);
    }
    m.insert("started_unix_ns".into(), now_ns().to_string());
    m.insert("instance".into(), args.process.instance.to_string());
    if let Some(man) = manifest {
        // The effective manifest: the file with the run's overrides applied.
        if let Ok(text) = man.to_toml() {
            m.insert("manifest".into(), text);
        }
        if let Some(src) = &man.run.source {
            m.insert("manifest_file".into(), src.clone());
        }
        m.insert("seed".into(), man.run.seed.to_string());
        m.insert("clock".into(), man.run.clock.clone());
        m.insert("rate".into(), man.run.rate.to_string());
        m.insert("duration_s".into(), man.run.duration_s.to_string());
        if let Some(site) = &man.site {
            m.insert("origin_lat_deg".into(), site.latitude_deg.to_string());
            m.insert("origin_lon_deg".into(), site.longitude_deg.to_string());
            m.insert(
                "magnetic_declination_deg".into(),
                site.magnetic_declination_deg.to_string(),
            );
        }
        // The sensor configuration: every source process's section.
        for (name, p) in &man.processes {
            if p.bin == "nauta-sensor" {
                let mut t = toml::Table::new();
                t.insert("params".into(), toml::Value::Table(p.params.clone()));
                if let Some(v) = &p.variant {
                    t.insert("variant".into(), toml::Value::String(v.clone()));
                }
                for (v, table) in &p.variants {
                    t.insert(format!("variants.{v}"), toml::Value::Table(table.clone()));
                }
                m.insert(
                    format!("sensor_config.{name}"),
                    toml::to_string(&t).unwrap_or_default(),
                );
            }
        }
    }
    m
}

fn run(args: &Args) -> anyhow::Result<()> {
    check(args)?;
    let ns = args
        .process
        .namespace
        .as_deref()
        .context("--namespace is required")?;
    let namespace = Namespace::new(ns)?;
    let manifest = args
        .process
        .manifest
        .as_deref()
        .map(Manifest::load)
        .transpose()?;
    let mut settings = Context::settings(nauta_messages::Role::Logger);
    settings.process = args
        .process
        .process
        .clone()
        .unwrap_or_else(|| "logger".into());
    settings.instance = args.process.instance;
    settings.variant = "mcap".into();
    if let Some(m) = &manifest {
        settings.clock = m.clock();
        settings.deadline = Duration::from_millis(m.run.backpressure_deadline_ms);
    }
    let template = args.output.as_ref().context("-o FILE is required")?;
    let path = output_path(template, ns, args.process.instance);

    let mut ctx = Context::new(&namespace, settings)?;
    let mut writer = LogWriter::create(&path, WriterOptions::default())?;
    writer.metadata(
        nauta_log::META_RUN,
        run_metadata(args, manifest.as_ref(), ns),
    )?;
    writer.flush()?;
    let result = record(&mut ctx, &mut writer, &path, args.follow_pid);
    // Whatever happened, the file gets its summary.
    let finished = writer.finish();
    ctx.finish();
    result.and(finished)
}

fn alive(pid: u32) -> bool {
    // SAFETY: kill(2) with signal 0 only checks that the process exists.
    pid > 0 && unsafe { libc::kill(pid as i32, 0) } == 0
}

fn record(
    ctx: &mut Context,
    writer: &mut LogWriter,
    path: &Path,
    follow_pid: Option<u32>,
) -> anyhow::Result<()> {
    let mut health = HealthReporter::new(ctx)?;
    let mut known = BTreeSet::new();
    let mut taps: Vec<Box<dyn RecordingTap>> = Vec::new();
    let mut inboxes = Vec::new();
    for (t, i) in discovery::open_new(ctx, writer, &mut known)? {
        taps.push(t);
        inboxes.push(i);
    }
    for t in &taps {
        t.connect()?;
    }
    tracing::info!(file = %path.display(), services = taps.len(), "recording");
    ctx.ready();
    health.state = nauta_messages::state::RUNNING;

    let mut last_flush = Instant::now();
    let mut last_discovery = Instant::now();
    let mut last_health = Instant::now();
    let mut stop = false;
    loop {
        let mut found = Vec::new();
        let exit = {
            let inbox_refs: Vec<_> = inboxes.iter().collect();
            EventLoop::new(Duration::from_millis(100)).run(&inbox_refs, |wake| {
                let now = now_ns();
                for t in taps.iter_mut() {
                    health.inputs += t.drain(writer, now)? as u64;
                }
                if last_flush.elapsed() >= FLUSH_PERIOD {
                    writer.flush()?;
                    last_flush = Instant::now();
                }
                if wake == Wake::Tick {
                    if last_health.elapsed() >= Duration::from_secs(1) {
                        health.outputs = writer.written();
                        health.dropped = taps.iter().map(|t| t.gaps().missing).sum();
                        health.last_stamp_ns =
                            taps.iter().map(|t| t.last_stamp_ns()).max().unwrap_or(0);
                        health.publish(ctx);
                        last_health = Instant::now();
                    }
                    if let Some(pid) = follow_pid
                        && !alive(pid)
                    {
                        tracing::info!(pid, "the run's launcher has exited");
                        stop = true;
                        return Ok(ControlFlow::Break(()));
                    }
                    if last_discovery.elapsed() >= DISCOVERY_PERIOD {
                        last_discovery = Instant::now();
                        found = discovery::open_new(ctx, writer, &mut known)?;
                        if !found.is_empty() {
                            return Ok(ControlFlow::Break(()));
                        }
                    }
                }
                Ok(ControlFlow::Continue(()))
            })?
        };
        match exit {
            LoopExit::Signal => break,
            LoopExit::Finished if stop => break,
            LoopExit::Finished => {
                for (t, i) in found {
                    tracing::info!(service = t.topic(), "recording a new service");
                    t.connect()?;
                    taps.push(t);
                    inboxes.push(i);
                }
            }
        }
    }
    // Stopped: take what is still queued (the publishers have stopped before
    // the logger), then the counts.
    let now = now_ns();
    for t in taps.iter_mut() {
        health.inputs += t.drain(writer, now)? as u64;
    }
    let mut stats = BTreeMap::new();
    for t in &taps {
        let g = t.gaps();
        stats.insert(
            t.topic().to_owned(),
            format!(
                "received={} gaps={} out_of_order={}",
                t.received(),
                g.missing,
                g.out_of_order
            ),
        );
    }
    writer.metadata(nauta_log::META_STATS, stats)?;
    let gaps: u64 = taps.iter().map(|t| t.gaps().missing).sum();
    tracing::info!(
        file = %path.display(),
        messages = writer.written(),
        channels = taps.len(),
        gaps,
        "recording finished"
    );
    Ok(())
}
