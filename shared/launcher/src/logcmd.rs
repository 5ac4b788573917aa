//! `nauta log info`, `nauta record`, `nauta replay`: recordings (DESIGN §8).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Context as _;

/// Arguments of `nauta log info`.
#[derive(Debug, clap::Args)]
pub struct InfoArgs {
    /// The recording (MCAP).
    pub file: PathBuf,
    /// Print one JSON object (`{"channels": [...], "truncated": ..., ...}`).
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `nauta record`.
#[derive(Debug, clap::Args)]
pub struct RecordArgs {
    /// Output file (MCAP).
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
    /// The run to record, when several are running.
    #[arg(long)]
    pub namespace: Option<String>,
}

/// Arguments of `nauta replay`.
#[derive(Debug, clap::Args)]
pub struct ReplayArgs {
    /// The recording to replay.
    pub file: PathBuf,
    /// Pace at X times the recorded speed (wall clock).
    #[arg(long, conflicts_with = "fast", allow_negative_numbers = true)]
    pub rate: Option<f64>,
    /// As fast as the pipeline consumes (sim clock, deterministic).
    #[arg(long)]
    pub fast: bool,
    /// Run this manifest's estimators instead of the recorded manifest's.
    #[arg(long)]
    pub manifest: Option<PathBuf>,
    /// Record the replayed run to this file (MCAP).
    #[arg(long, value_name = "OUT")]
    pub record: Option<PathBuf>,
    /// Override a manifest value, as `nauta launch --set`.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
}

/// `nauta log info FILE [--json]`.
pub fn info(args: &InfoArgs) -> anyhow::Result<ExitCode> {
    let total = std::fs::metadata(&args.file).map(|m| m.len()).unwrap_or(0);
    let bar = nauta_tools::progress::progress_bar(total, "reading");
    let info = nauta_log::info::summarise(&args.file, |done, _| bar.set_position(done))?;
    bar.finish_and_clear();
    if args.json {
        println!("{}", serde_json::to_string_pretty(&info)?);
        return Ok(ExitCode::SUCCESS);
    }
    println!("{}", info.file);
    let r = &info.recovery;
    if info.truncated {
        println!(
            "  TRUNCATED: read {} of {} bytes ({} lost), {} complete chunks{}",
            r.read_bytes,
            r.file_bytes,
            r.lost_bytes(),
            r.chunks,
            r.reason
                .as_ref()
                .map(|w| format!(": {w}"))
                .unwrap_or_default()
        );
    } else {
        println!("  complete: {} bytes, {} chunks", r.file_bytes, r.chunks);
    }
    if r.damaged_chunks > 0 {
        println!(
            "  DAMAGED: {} chunks skipped (nothing in them used)",
            r.damaged_chunks
        );
    }
    for note in r.damage_notes() {
        println!("    {note}");
    }
    println!(
        "  span {:.3} s .. {:.3} s ({:.1} s), {} messages, {} gaps",
        info.start_stamp_ns as f64 * 1e-9,
        info.end_stamp_ns as f64 * 1e-9,
        info.duration_s,
        info.messages,
        info.gaps
    );
    println!(
        "  {:<22} {:<28} {:>9} {:>9} {:>6} {:>9}",
        "channel", "type", "count", "rate Hz", "gaps", "instances"
    );
    for c in &info.channels {
        println!(
            "  {:<22} {:<28} {:>9} {:>9.2} {:>6} {:>9}",
            c.topic, c.type_name, c.count, c.rate_hz, c.gaps, c.instances
        );
    }
    for (name, entries) in &info.metadata {
        println!("  metadata {name}:");
        for (k, v) in entries {
            let first = v.lines().next().unwrap_or("");
            let more = v.lines().count() > 1;
            println!("    {k}: {first}{}", if more { " ..." } else { "" });
        }
    }
    if !info.events.is_empty() {
        println!("  events:");
        for e in &info.events {
            println!(
                "    {:>10.3} s {:<10} {} #{} pid {} {}{}",
                e.stamp_ns as f64 * 1e-9,
                e.kind,
                e.process,
                e.instance,
                e.pid,
                e.variant,
                if e.kind == "exited" {
                    format!(" exit {}", e.exit_code)
                } else {
                    String::new()
                }
            );
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// `nauta record -o FILE`: becomes a logger attached to the running
/// pipeline (`nauta-logger`, which stops when the run's launcher exits or on
/// Ctrl-C).
pub fn record(args: &RecordArgs) -> anyhow::Result<ExitCode> {
    use std::os::unix::process::CommandExt as _;
    crate::launch::check_output_parent(&args.output)?;
    let run = crate::pipeline::find(args.namespace.as_deref())?;
    let manifest = crate::launch::runs_dir()?
        .join(&run.namespace)
        .join("manifest.toml");
    // The logger reads it: only a file of this user, in this user's private
    // run directory, is handed over.
    nauta_runtime::run_files::check_private_dir(manifest.parent().unwrap_or(&manifest))?;
    nauta_runtime::run_files::read_owned(&manifest, 64 << 20)?;
    let bin = crate::children::find_binary(crate::launch::LOGGER_BIN)?;
    eprintln!(
        "nauta: recording run {} ({}) to {}",
        run.namespace,
        run.manifest,
        args.output.display()
    );
    let err = std::process::Command::new(&bin)
        .arg("--manifest")
        .arg(&manifest)
        .args(["--process", "record", "--namespace", &run.namespace])
        .arg("-o")
        .arg(&args.output)
        .args(["--follow-pid", &run.launcher_pid.to_string()])
        .env(
            "NAUTA_COMMAND_LINE",
            std::env::args().collect::<Vec<_>>().join(" "),
        )
        .exec();
    Err(anyhow::anyhow!("cannot run {}: {err}", bin.display()))
}

/// The manifest a replay runs: the recorded one (or `--manifest`), with its
/// sensor reading the recording (`--from`) and without its logger (which would
/// write over the recording; `--record` adds one).
fn replay_manifest(args: &ReplayArgs, file: &std::path::Path) -> anyhow::Result<toml::Table> {
    let (text, origin) = match &args.manifest {
        Some(m) => (
            std::fs::read_to_string(m).with_context(|| format!("cannot read {}", m.display()))?,
            m.display().to_string(),
        ),
        None => {
            let rec = nauta_log::read(file, |_, _| Ok(()))?;
            for note in rec.recovery.damage_notes() {
                eprintln!("nauta replay: note: {note}");
            }
            let text = rec
                .metadata(nauta_log::META_RUN)
                .and_then(|m| m.get("manifest"))
                .cloned()
                .with_context(|| {
                    format!(
                        "{} holds no manifest (metadata {}); give one with --manifest",
                        file.display(),
                        nauta_log::META_RUN
                    )
                })?;
            (text, format!("the manifest recorded in {}", file.display()))
        }
    };
    let mut table: toml::Table =
        toml::from_str(&text).with_context(|| format!("cannot parse {origin}"))?;
    let processes = table
        .get_mut("process")
        .and_then(toml::Value::as_table_mut)
        .with_context(|| format!("{origin} has no [process.*]"))?;
    let bin_of = |p: &toml::Value| {
        p.get("bin")
            .and_then(toml::Value::as_str)
            .map(str::to_owned)
    };
    processes.retain(|_, p| bin_of(p).as_deref() != Some(crate::launch::LOGGER_BIN));
    if args.manifest.is_none() {
        // A recording is data, not a program: its manifest may only start
        // nauta's own service binaries, from beside this `nauta`.
        for (name, p) in processes.iter_mut() {
            let bin = bin_of(p).unwrap_or_default();
            let path = crate::children::find_service_binary(&bin).with_context(|| {
                format!(
                    "{origin}: process.{name}.bin: refusing to run {bin:?} from a recording; give your own manifest with --manifest to run other programs"
                )
            })?;
            if let Some(t) = p.as_table_mut() {
                t.insert("bin".into(), path.display().to_string().into());
            }
        }
    }
    let mut sensors = 0;
    for (_, p) in processes.iter_mut() {
        if bin_of(p).as_deref().and_then(|b| Path::new(b).file_name())
            == Some(std::ffi::OsStr::new("nauta-sensor"))
            && let Some(t) = p.as_table_mut()
        {
            t.insert(
                "args".into(),
                toml::Value::Array(vec!["--from".into(), file.display().to_string().into()]),
            );
            sensors += 1;
        }
    }
    anyhow::ensure!(
        sensors > 0,
        "{origin} has no nauta-sensor process to replay through"
    );
    Ok(table)
}

/// Refuses to record a replay into the recording it reads (the same path,
/// through any link, or the same file).
fn refuse_same_file(input: &Path, output: &Path) -> anyhow::Result<()> {
    use std::os::unix::fs::MetadataExt as _;
    let same_inode = match (std::fs::metadata(input), std::fs::metadata(output)) {
        (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
        _ => false,
    };
    let canonical = |p: &Path| {
        let parent = p
            .parent()
            .filter(|d| !d.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        std::fs::canonicalize(parent)
            .ok()
            .zip(p.file_name())
            .map(|(d, n)| d.join(n))
    };
    let same_path = canonical(input).is_some_and(|a| Some(a) == canonical(output));
    anyhow::ensure!(
        !(same_inode || same_path),
        "--record {} is the recording being replayed; choose another output file",
        output.display()
    );
    Ok(())
}

/// `nauta replay FILE`: runs the recorded pipeline (or `--manifest`) with the
/// sensor republishing the recording.
pub fn replay(args: &ReplayArgs) -> anyhow::Result<ExitCode> {
    let file = std::path::absolute(&args.file)
        .with_context(|| format!("cannot resolve {}", args.file.display()))?;
    if let Some(out) = &args.record {
        refuse_same_file(&file, out)?;
    }
    let table = replay_manifest(args, &file)?;
    let manifest =
        crate::launch::runs_dir()?.join(nauta_runtime::run_files::unique_name("replay", "toml"));
    nauta_runtime::run_files::create_file(&manifest, toml::to_string(&table)?.as_bytes())?;
    let launch = crate::launch::LaunchArgs {
        manifest: manifest.clone(),
        clock: args.rate.map(|_| "wall".to_owned()),
        fast: args.fast,
        rate: args.rate,
        duration: None,
        seed: None,
        namespace: None,
        set: args.set.clone(),
        record: args.record.clone(),
    };
    eprintln!("nauta: replaying {}", file.display());
    let result = crate::launch::run(&launch);
    let _ = std::fs::remove_file(&manifest);
    result.map(ExitCode::from)
}
