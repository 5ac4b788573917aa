//! `nauta launch`: run a pipeline from a manifest (DESIGN §5, §9).

use std::collections::BTreeMap;
use std::ops::ControlFlow;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::{Context as _, bail};
use nauta_messages::*;
use nauta_runtime::ports::Inbox;
use nauta_runtime::run_files;
use nauta_runtime::{
    Context, ControlClient, Describe, EventLoop, LoopExit, Manifest, Namespace, PipelineServer,
    Wake, services,
};

use crate::children;
use crate::monitor::{self, Observer, Tap};
use crate::pipeline::StatusWriter;
pub use crate::rundir::runs_dir;
use crate::rundir::{claim_run_dir, cleanup_stale_runs};
use crate::summary::{Report, RunSummary};
use crate::supervisor::{Outcome, Restart, Supervisor};

/// Options of `nauta launch`.
#[derive(Debug, Clone, clap::Args)]
pub struct LaunchArgs {
    /// The manifest (e.g. launch/survey.toml).
    pub manifest: PathBuf,
    /// Clock: `sim` (as fast as possible, deterministic) or `wall` (real time).
    #[arg(long)]
    pub clock: Option<String>,
    /// Same as `--clock sim`.
    #[arg(long, conflicts_with = "clock")]
    pub fast: bool,
    /// Pace `wall` at this multiple of real time.
    #[arg(long, allow_negative_numbers = true)]
    pub rate: Option<f64>,
    /// Mission duration in simulated seconds.
    #[arg(long, allow_negative_numbers = true)]
    pub duration: Option<f64>,
    /// Seed of every random generator of the run (0 to 2^63 - 1, as in the manifest).
    #[arg(long, allow_negative_numbers = true, value_parser = clap::value_parser!(u64).range(..=i64::MAX as u64))]
    pub seed: Option<u64>,
    /// Run in this namespace instead of a unique one.
    #[arg(long)]
    pub namespace: Option<String>,
    /// Override a manifest value: `run.KEY=VALUE` or `PROCESS.KEY=VALUE`
    /// (`process.NAME.KEY=VALUE` may add a process).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Record the whole run to FILE (MCAP): adds a logger process (restarted
    /// on failure, into FILE.K.mcap) or points the manifest's logger there.
    #[arg(long, value_name = "FILE")]
    pub record: Option<PathBuf>,
}

/// `nauta launch`: [`LaunchArgs`] and how to print the summary.
#[derive(Debug, Clone, clap::Args)]
pub struct LaunchCommand {
    #[command(flatten)]
    pub args: LaunchArgs,
    /// Print the run summary as one JSON object on stdout (keys in the
    /// README, "The run summary") instead of one line.
    #[arg(long)]
    pub json: bool,
}

/// How long a process may take to report ready.
const READY_TIMEOUT: Duration = Duration::from_secs(30);
/// How long a process may take to stop after SIGTERM before it is killed.
const STOP_TIMEOUT: Duration = Duration::from_secs(5);

#[derive(Debug, Clone)]
struct Proc {
    name: String,
    bin: PathBuf,
    describe: Describe,
    /// Its optional inputs that no process of the run publishes (passed as
    /// `--absent SERVICE`).
    absent: Vec<String>,
}

impl Proc {
    fn is_logger(&self) -> bool {
        self.describe.role == Role::Logger.name()
    }
}

/// A checked manifest and its processes in start order.
#[derive(Debug)]
pub struct Plan {
    /// The effective manifest (overrides applied).
    pub manifest: Manifest,
    procs: Vec<Proc>,
}

/// The binary of the logger role.
pub const LOGGER_BIN: &str = "nauta-logger";

/// Options shared by `nauta launch` and `nauta check` that change the manifest.
fn overrides(args: &LaunchArgs) -> Vec<String> {
    let mut overrides = args.set.clone();
    if let Some(file) = &args.record {
        // The manifest's own logger, if it has one, else a new one.
        let existing = std::fs::read_to_string(&args.manifest)
            .ok()
            .and_then(|t| toml::from_str::<toml::Table>(&t).ok())
            .and_then(|t| {
                t.get("process")?.as_table()?.iter().find_map(|(name, p)| {
                    (p.get("bin")?.as_str()? == LOGGER_BIN).then(|| name.clone())
                })
            });
        let file = toml::Value::String(file.display().to_string());
        match existing {
            Some(name) => overrides.push(format!("{name}.args=[\"-o\", {file}]")),
            None => {
                overrides.push(format!("process.logger.bin=\"{LOGGER_BIN}\""));
                overrides.push(format!("process.logger.args=[\"-o\", {file}]"));
                overrides.push(
                    "process.logger.restart={ policy = \"on-failure\", max = 5, window_s = 60 }"
                        .into(),
                );
            }
        }
    }
    if args.fast {
        overrides.push("run.clock=\"sim\"".into());
    }
    if let Some(c) = &args.clock {
        overrides.push(format!("run.clock=\"{c}\""));
    }
    if let Some(r) = args.rate {
        overrides.push(format!("run.rate={}", toml_float(r)));
    }
    if let Some(d) = args.duration {
        overrides.push(format!("run.duration_s={}", toml_float(d)));
    }
    if let Some(s) = args.seed {
        overrides.push(format!("run.seed={s}"));
    }
    overrides
}

/// `x` as a TOML float, so that the manifest's range check names the key
/// (`NaN` is no TOML; `nan` is).
fn toml_float(x: f64) -> String {
    if x.is_nan() {
        "nan".into()
    } else if x.is_infinite() {
        if x > 0.0 { "inf" } else { "-inf" }.into()
    } else {
        format!("{x:?}")
    }
}

/// Reads and checks a manifest with its overrides: schema and values, every
/// binary found and described, every chosen variant implemented, the wiring.
/// Nothing is started. Errors name the file, the line and the key.
pub fn prepare(path: &std::path::Path, overrides: &[String]) -> anyhow::Result<Plan> {
    let manifest = Manifest::load_with(path, overrides)?;
    let mut procs = Vec::new();
    for (name, p) in &manifest.processes {
        let bin = children::find_binary(&p.bin)
            .map_err(|e| manifest.error_at(&format!("process.{name}.bin"), e))?;
        let describe = children::describe(&bin)
            .map_err(|e| manifest.error_at(&format!("process.{name}.bin"), format!("{e:#}")))?;
        if let Some(v) = &p.variant
            && !describe.variants.contains(v)
        {
            return Err(manifest.error_at(
                &format!("process.{name}.variant"),
                format!(
                    "{} does not implement {v:?} (it has {:?})",
                    p.bin, describe.variants
                ),
            ));
        }
        for v in p.variants.keys() {
            if !describe.variants.contains(v) {
                return Err(manifest.error_at(
                    &format!("process.{name}.variants.{v}"),
                    format!(
                        "{} has no variant {v:?} (it has {:?})",
                        p.bin, describe.variants
                    ),
                ));
            }
        }
        if describe.is_source()
            && let Some(r) = &p.restart
            && r.policy != "never"
        {
            return Err(manifest.error_at(
                &format!("process.{name}.restart.policy"),
                format!(
                    "{} is a data source: restarting it would start its data over; use \"never\"",
                    p.bin
                ),
            ));
        }
        procs.push(Proc {
            name: name.clone(),
            bin,
            describe,
            absent: Vec::new(),
        });
    }
    check_wiring(&manifest, &procs)?;
    let published: std::collections::BTreeSet<String> = procs
        .iter()
        .flat_map(|p| p.describe.outputs.iter().map(|o| o.service.clone()))
        .collect();
    for p in &mut procs {
        p.absent = p
            .describe
            .inputs
            .iter()
            .filter(|i| i.optional && !published.contains(&i.service))
            .map(|i| i.service.clone())
            .collect();
    }
    check_roles(&manifest, &procs)?;
    check_parameters(&manifest, &procs)?;
    // Sources first (in standby: see docs/design-notes.md), then consumers,
    // each after the processes its `after` names, then the logger, which
    // subscribes to the services that exist once everyone else is ready.
    let order = manifest.start_order(|n| match procs.iter().find(|p| p.name == n) {
        Some(p) if p.describe.is_source() => 0,
        Some(p) if p.is_logger() => 2,
        _ => 1,
    });
    let procs = order
        .iter()
        .filter_map(|n| procs.iter().position(|p| &p.name == n))
        .map(|i| procs[i].clone())
        .collect();
    Ok(Plan { manifest, procs })
}

/// One process per role: services, control addresses and snapshots are per
/// role, so two processes of one role would publish into each other's
/// streams.
fn check_roles(manifest: &Manifest, procs: &[Proc]) -> anyhow::Result<()> {
    let mut by_role: BTreeMap<&str, &str> = BTreeMap::new();
    for p in procs {
        if let Some(first) = by_role.insert(&p.describe.role, &p.name) {
            return Err(manifest.error_at(
                &format!("process.{}.bin", p.name),
                format!(
                    "processes {first} and {} both have role {}: a run has one process per role",
                    p.name, p.describe.role
                ),
            ));
        }
    }
    Ok(())
}

/// `--record FILE` and `nauta record -o FILE`: FILE's directory must exist
/// (nothing creates directories on the user's behalf).
pub fn check_output_parent(file: &std::path::Path) -> anyhow::Result<()> {
    let parent = file
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(std::path::Path::new("."));
    anyhow::ensure!(
        parent.is_dir(),
        "cannot record to {}: the directory {} does not exist",
        file.display(),
        parent.display()
    );
    Ok(())
}

/// Every binary checks its own parameters in the effective manifest
/// (`--check`), so a wrong value stops the run before anything starts.
fn check_parameters(manifest: &Manifest, procs: &[Proc]) -> anyhow::Result<()> {
    let file = runs_dir()?.join(run_files::unique_name("check", "toml"));
    run_files::create_file(&file, manifest.to_toml()?.as_bytes())?;
    let result = procs.iter().try_for_each(|p| {
        let variant = manifest.process(&p.name)?.variant.as_deref();
        children::check(&p.bin, &file, &p.name, variant)
    });
    let _ = std::fs::remove_file(&file);
    result
}

/// `nauta check`: validates only; prints one line per process.
pub fn check(args: &LaunchArgs) -> anyhow::Result<()> {
    if let Some(f) = &args.record {
        check_output_parent(f)?;
    }
    let plan = prepare(&args.manifest, &overrides(args))?;
    let m = &plan.manifest;
    println!(
        "{}: ok: {} clock, {} s, seed {}, {} processes",
        args.manifest.display(),
        m.clock().name(),
        m.run.duration_s,
        m.run.seed,
        plan.procs.len()
    );
    for p in &plan.procs {
        let section = m.process(&p.name)?;
        let variant = section
            .variant
            .clone()
            .or_else(|| p.describe.variants.first().cloned())
            .unwrap_or_default();
        println!(
            "  {:<12} {} [{variant}]{} inputs {}, outputs {}{}",
            p.name,
            p.bin.display(),
            if p.describe.is_source() {
                " source,"
            } else {
                ""
            },
            p.describe.inputs.len(),
            p.describe.outputs.len(),
            if section.after.is_empty() {
                String::new()
            } else {
                format!(", after {}", section.after.join(", "))
            }
        );
    }
    Ok(())
}

/// Runs the pipeline and prints its summary line; returns the process exit code.
pub fn run(args: &LaunchArgs) -> anyhow::Result<u8> {
    let summary = run_to_summary(args)?;
    println!("{}", summary.line());
    Ok(summary.exit_code)
}

/// `nauta launch`: runs the pipeline and prints its summary, as one line or
/// (`--json`) one JSON object; returns the process exit code.
pub fn launch(cmd: &LaunchCommand) -> anyhow::Result<u8> {
    let summary = run_to_summary(&cmd.args)?;
    if cmd.json {
        println!("{}", serde_json::to_string(&summary)?);
    } else {
        println!("{}", summary.line());
    }
    Ok(summary.exit_code)
}

/// Runs the pipeline to its end; its summary.
fn run_to_summary(args: &LaunchArgs) -> anyhow::Result<RunSummary> {
    if let Some(f) = &args.record {
        check_output_parent(f)?;
    }
    let Plan { manifest, procs } = prepare(&args.manifest, &overrides(args))?;
    let namespace = match (&args.namespace, manifest.run.namespace.as_str()) {
        (Some(ns), _) => Namespace::new(ns)?,
        (None, "auto") => Namespace::unique(),
        (None, ns) => Namespace::new(ns)?,
    };

    let (run_dir, _lock) = claim_run_dir(&namespace)?;
    let removed = cleanup_stale_runs();
    if removed > 0 {
        tracing::info!(
            removed,
            "removed files left by dead processes of earlier runs"
        );
    }
    let manifest_file = run_dir.join("manifest.toml");
    run_files::create_file(&manifest_file, manifest.to_toml()?.as_bytes())?;

    let mut settings = Context::settings(Role::Launcher);
    settings.process = "launcher".into();
    settings.clock = manifest.clock();
    settings.deadline = Duration::from_millis(manifest.run.backpressure_deadline_ms);
    let mut ctx = Context::new(&namespace, settings)?;
    let (mut events, events_inbox) = ctx.subscriber(&services::run_events())?;

    // Taps on every output and on each process's health, opened before any
    // process starts so nothing is missed.
    let mut taps: Vec<Box<dyn Tap>> = Vec::new();
    let mut inboxes: Vec<Inbox> = Vec::new();
    let mut seen = std::collections::BTreeSet::new();
    for p in &procs {
        for o in &p.describe.outputs {
            if seen.insert(o.service.clone()) {
                let (t, i) = monitor::tap(&ctx, &o.service, &o.type_name)?;
                taps.push(t);
                inboxes.push(i);
            }
        }
        let health = services::health(Role::from_name(&p.describe.role).unwrap_or(Role::Unknown));
        if seen.insert(health.name.clone()) {
            let (t, i) = monitor::tap(&ctx, &health.name, health.type_name())?;
            taps.push(t);
            inboxes.push(i);
        }
    }

    // Every process opens its ports and reports ready once its inputs are
    // connected to their publishers. Sources start in standby (they publish
    // nothing yet), so they go first: their publishers are what consumers wait
    // for. Once all are ready and the launcher's own taps are connected, the
    // sources are activated: nothing is published before everyone listens.
    let started = Instant::now();
    let mut sup = Supervisor::new(&manifest_file, &run_dir, namespace.as_str());
    let mut observer = Observer::default();
    eprintln!(
        "nauta: run {namespace}: {} clock, {} s mission, seed {}",
        manifest.clock().name(),
        manifest.run.duration_s,
        manifest.run.seed
    );
    let startup = (|| -> anyhow::Result<()> {
        let mut ready = std::collections::BTreeSet::new();
        for p in &procs {
            let section = manifest.process(&p.name)?;
            if !section.after.is_empty() {
                wait_ready(&ctx, &mut events, &mut sup, &mut ready, &section.after)?;
            }
            if p.is_logger() {
                // Every other process has opened its publishers once it is
                // ready: the logger then finds and attaches to all of them
                // before the sources are activated.
                let before: Vec<String> = sup.members.iter().map(|m| m.name.clone()).collect();
                wait_ready(&ctx, &mut events, &mut sup, &mut ready, &before)?;
            }
            let mut args = section.args.clone();
            for s in &p.absent {
                args.extend(["--absent".to_owned(), s.clone()]);
            }
            sup.start(
                &p.name,
                &p.bin,
                &p.describe,
                section.variant.as_deref(),
                &args,
                Restart::from_section(section.restart.as_ref()),
            )?;
        }
        let everyone: Vec<String> = sup.members.iter().map(|m| m.name.clone()).collect();
        wait_ready(&ctx, &mut events, &mut sup, &mut ready, &everyone)?;
        connect_taps(&ctx, &taps)?;
        if procs.iter().any(Proc::is_logger) {
            sup.announce_running(&mut ctx);
        }
        for p in procs.iter().filter(|p| p.describe.is_source()) {
            activate(&ctx, p)?;
        }
        Ok(())
    })();
    if let Err(e) = startup {
        stop_all(&mut sup);
        drop((taps, inboxes, events, events_inbox));
        ctx.finish();
        let _ = std::fs::remove_dir_all(&run_dir);
        return Err(e);
    }

    let mut failure = None;
    let mut stop_requested = false;
    // READY events by (process, instance): a swapped-in instance is switched
    // to once it is ready.
    let mut ready_instances = std::collections::BTreeSet::new();
    let (mut pipeline, pipeline_inbox) =
        PipelineServer::open_named(&ctx, &nauta_runtime::control::pipeline_control_name())?;
    let mut status = StatusWriter::new(
        &run_dir,
        namespace.as_str(),
        &args.manifest,
        manifest.clock().name(),
    );
    status.update(&mut sup, &observer, true);
    let exit = {
        let mut inbox_refs: Vec<&Inbox> = inboxes.iter().collect();
        inbox_refs.push(&pipeline_inbox);
        EventLoop::new(Duration::from_millis(50)).run(&inbox_refs, |wake| {
            for t in taps.iter_mut() {
                t.drain(&mut observer)?;
            }
            let mut changed = false;
            pipeline.serve(|req| {
                let process = fixed_str(&req.process);
                let variant = fixed_str(&req.variant);
                let result = match req.command {
                    pipeline_command::STOP => {
                        stop_requested = true;
                        Ok(())
                    }
                    pipeline_command::RESTART => sup.request_restart(&process, None),
                    pipeline_command::SWAP => sup.request_restart(&process, Some(&variant)),
                    _ => Err((pipeline_status::UNKNOWN_COMMAND, "unknown command".into())),
                };
                let (status, detail) = match result {
                    Ok(()) => {
                        changed = true;
                        (pipeline_status::OK, String::new())
                    }
                    Err((code, why)) => (code, why),
                };
                tracing::info!(command = req.command, %process, %variant, status, %detail, "pipeline command");
                PipelineResponse {
                    header: Header::new(0, 0, Role::Launcher, 0),
                    status,
                    pad: 0,
                    detail: to_fixed_str(&detail),
                }
            })?;
            if stop_requested {
                eprintln!("nauta: stopping on request (nauta stop)");
                return Ok(ControlFlow::Break(()));
            }
            if wake == Wake::Tick || changed {
                status.update(&mut sup, &observer, changed);
            }
            if wake == Wake::Tick {
                let mut logger_restarted = false;
                let _ = events.drain(|e| {
                    if e.kind == event_kind::READY {
                        ready_instances.insert((fixed_str(&e.process), e.instance));
                        logger_restarted |= e.role == Role::Logger as u32 && e.instance > 0;
                    }
                });
                if logger_restarted {
                    // Its new file starts with who runs, as the first one did.
                    sup.announce_running(&mut ctx);
                }
                match sup.tick(&mut ctx, &mut taps, &mut observer, &ready_instances)? {
                    Outcome::Running => {}
                    Outcome::Finished => {
                        for t in taps.iter_mut() {
                            t.drain(&mut observer)?;
                        }
                        return Ok(ControlFlow::Break(()));
                    }
                    Outcome::Failed(why) => {
                        tracing::error!("{why}; stopping the run");
                        failure = Some(why);
                        return Ok(ControlFlow::Break(()));
                    }
                }
            }
            Ok(ControlFlow::Continue(()))
        })?
    };
    if exit == LoopExit::Signal {
        eprintln!("nauta: stopping on signal");
    }
    sup.end_swaps();
    stop_all(&mut sup);
    for t in taps.iter_mut() {
        t.drain(&mut observer)?;
    }
    let wall = started.elapsed();
    let mut failures = failures(&mut sup);
    if let Some(f) = failure
        && !failures.contains(&f)
    {
        failures.insert(0, f);
    }
    let summary = RunSummary::new(
        Report {
            manifest: &manifest,
            ns: &namespace,
            wall,
            taps: &taps,
            sup: &sup,
            failures,
            exit,
            stopped_by_request: stop_requested,
        },
        &mut observer,
    );
    drop(taps);
    drop(inboxes);
    drop(events);
    drop(events_inbox);
    drop((pipeline, pipeline_inbox));
    ctx.finish();
    let _ = std::fs::remove_dir_all(&run_dir);
    Ok(summary)
}

/// What went wrong: processes that failed beyond their policy, and the last
/// instance of any process that did not exit 0 in the end.
fn failures(sup: &mut Supervisor) -> Vec<String> {
    let mut out: Vec<String> = sup
        .members
        .iter()
        .filter_map(|m| m.failure.clone())
        .collect();
    for m in sup.members.iter_mut() {
        m.child.poll();
        let code = m.child.code();
        let line = format!(
            "{} exited {}",
            m.name,
            code.map_or("?".into(), |c| c.to_string())
        );
        if code != Some(0) && !out.iter().any(|f| f.starts_with(&format!("{} ", m.name))) {
            out.push(line);
        }
    }
    out
}

fn check_wiring(manifest: &Manifest, procs: &[Proc]) -> anyhow::Result<()> {
    let mut published: BTreeMap<&str, (&str, &str)> = BTreeMap::new();
    for p in procs {
        for o in &p.describe.outputs {
            published.insert(&o.service, (&o.type_name, &p.name));
        }
    }
    for p in procs {
        for i in &p.describe.inputs {
            match published.get(i.service.as_str()) {
                None if i.optional => {}
                None => {
                    return Err(manifest.error_at(
                        &format!("process.{}.bin", p.name),
                        format!(
                            "{} subscribes to {} ({}), which no process publishes",
                            p.describe.role, i.service, i.type_name
                        ),
                    ));
                }
                Some((t, by)) if *t != i.type_name => {
                    return Err(manifest.error_at(
                        &format!("process.{}.bin", p.name),
                        format!(
                            "{} subscribes to {} as {}, but process {by} publishes it as {t}",
                            p.describe.role, i.service, i.type_name
                        ),
                    ));
                }
                Some(_) => {}
            }
        }
    }
    // A process reports ready only once its inputs' publishers exist, so a
    // publisher must not wait (`after`) for one of its own subscribers.
    for p in procs {
        let Ok(section) = manifest.process(&p.name) else {
            continue;
        };
        for a in &section.after {
            let Some(waited) = procs.iter().find(|q| &q.name == a) else {
                continue;
            };
            if let Some(i) = waited.describe.inputs.iter().find(|i| {
                !i.optional
                    && published
                        .get(i.service.as_str())
                        .is_some_and(|(_, by)| *by == p.name)
            }) {
                return Err(manifest.error_at(
                    &format!("process.{}.after", p.name),
                    format!(
                        "{a} cannot become ready before {} starts: it waits for {}, which {} publishes",
                        p.name, i.service, p.name
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Waits until every process in `names` has reported ready; `ready` keeps
/// the names seen so far across calls.
fn wait_ready(
    ctx: &Context,
    events: &mut nauta_runtime::Subscriber<RunEvent>,
    sup: &mut Supervisor,
    ready: &mut std::collections::BTreeSet<String>,
    names: &[String],
) -> anyhow::Result<()> {
    let t0 = Instant::now();
    loop {
        events.drain(|e| {
            if e.kind == event_kind::READY {
                ready.insert(fixed_str(&e.process));
            }
        })?;
        if names.iter().all(|n| ready.contains(n)) {
            return Ok(());
        }
        for r in sup.children_mut() {
            if r.poll() {
                bail!(
                    "process {} exited before it was ready (exit {:?})",
                    r.name,
                    r.code()
                );
            }
        }
        if t0.elapsed() > READY_TIMEOUT {
            let missing: Vec<&String> = names.iter().filter(|n| !ready.contains(*n)).collect();
            bail!("{missing:?} did not report ready within {READY_TIMEOUT:?}");
        }
        if !ctx.sleep(Duration::from_millis(2)) {
            bail!("interrupted while starting the run");
        }
    }
}

fn connect_taps(ctx: &Context, taps: &[Box<dyn Tap>]) -> anyhow::Result<()> {
    let t0 = Instant::now();
    loop {
        let mut all = true;
        for t in taps {
            all &= t.connect()?;
        }
        if all {
            return Ok(());
        }
        if t0.elapsed() > READY_TIMEOUT {
            bail!("the launcher could not connect to every output within {READY_TIMEOUT:?}");
        }
        if !ctx.sleep(Duration::from_millis(2)) {
            bail!("interrupted while starting the run");
        }
    }
}

fn activate(ctx: &Context, p: &Proc) -> anyhow::Result<()> {
    let role = Role::from_name(&p.describe.role)
        .with_context(|| format!("process {}: unknown role {:?}", p.name, p.describe.role))?;
    let client = ControlClient::open(ctx, role, 0)?;
    let req = ControlRequest {
        header: Header::new(0, 0, Role::Launcher, 0),
        command: command::ACTIVATE,
        pad: 0,
        boundary_stamp_ns: 0,
    };
    let resp = client.request(ctx, req, READY_TIMEOUT)?;
    anyhow::ensure!(
        resp.status == 0,
        "process {} refused to activate (status {})",
        p.name,
        resp.status
    );
    Ok(())
}

fn stop_all(sup: &mut Supervisor) {
    // Reverse start order: consumers before the sources they drain; the
    // logger last of all, so it records everything the others published.
    let (loggers, others): (Vec<_>, Vec<_>) = sup
        .members
        .iter_mut()
        .rev()
        .partition(|m| m.role == Role::Logger);
    for r in others.into_iter().chain(loggers).map(|m| &mut m.child) {
        if r.poll() {
            continue;
        }
        r.terminate();
        let t0 = Instant::now();
        while !r.poll() && t0.elapsed() < STOP_TIMEOUT {
            std::thread::sleep(Duration::from_millis(5));
        }
        if !r.poll() {
            tracing::warn!(process = %r.name, "did not stop within {STOP_TIMEOUT:?}; killing it");
            r.kill();
            let _ = r.child.wait().map(|s| r.status = Some(s));
        }
    }
}
