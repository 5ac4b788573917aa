//! `nauta`: the command-line front end (DESIGN §9).

use std::process::ExitCode;

use clap::{Parser, Subcommand};

use nauta_bench as bench;
use nauta_launcher::{launch, logcmd, pipeline};
use nauta_tools::{calibrate, eval, export, import, lbl_plan, report, smooth};

/// nauta: navigation stack of an autonomous underwater vehicle.
#[derive(Debug, Parser)]
#[command(name = "nauta", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run a pipeline from a manifest (e.g. `nauta launch launch/survey.toml --duration 60 --fast`).
    ///
    /// It runs the binaries the manifest names (as `cargo` runs build
    /// scripts): launch only manifests you trust.
    Launch(launch::LaunchCommand),
    /// Validate a manifest without starting a pipeline: schema and values, the
    /// binaries and their variants, the wiring (`nauta check launch/survey.toml`).
    ///
    /// It runs the binaries the manifest names (`--describe`, `--check`), as
    /// `cargo` runs build scripts: check only manifests you trust.
    Check(launch::LaunchArgs),
    /// Processes of the running pipeline: pid, variant, state, uptime, restarts, rates, losses.
    Status {
        /// Print one JSON object (`{"processes": [...]}`).
        #[arg(long)]
        json: bool,
        /// The run to show, when several are running.
        #[arg(long)]
        namespace: Option<String>,
    },
    /// Stop the running pipeline in order (as Ctrl-C in its shell would).
    Stop {
        /// The run to stop, when several are running.
        #[arg(long)]
        namespace: Option<String>,
    },
    /// Restart one process of the running pipeline (warm, from its latest snapshot).
    Restart {
        /// Process name in the manifest.
        process: String,
        /// The run, when several are running.
        #[arg(long)]
        namespace: Option<String>,
    },
    /// Swap one process of the running pipeline for another variant.
    Swap {
        /// Process name in the manifest.
        process: String,
        /// Variant to run instead.
        variant: String,
        /// The run, when several are running.
        #[arg(long)]
        namespace: Option<String>,
    },
    /// Attach a logger to the running pipeline and record it to FILE (MCAP) until
    /// the run ends or Ctrl-C.
    Record(logcmd::RecordArgs),
    /// Feed a recording's sensor channels into a pipeline (its recorded manifest
    /// unless `--manifest`), as the sensor process would.
    ///
    /// From a recorded manifest only nauta's own service binaries (beside
    /// `nauta`) are started; anything else is refused.
    Replay(logcmd::ReplayArgs),
    /// Recordings: `nauta log info FILE [--json]`.
    Log {
        #[command(subcommand)]
        which: LogCommand,
    },
    /// Accuracy of every estimate stream of a recording against the truth
    /// (simulator) or against surface GPS fixes (real data).
    Eval(eval::EvalArgs),
    /// Convert a recording for Google Earth (kml), GIS (geojson, gpx),
    /// spreadsheets (csv) or Foxglove (foxglove: MCAP with JSON messages).
    Export(export::ExportArgs),
    /// PNG plots of a recording and an index.html with the eval table.
    Report(report::ReportArgs),
    /// Sensor calibration: `nauta calibrate magnetometer launch/survey.toml`
    /// prints the attitude parameters that remove the magnetometer's hard and
    /// soft iron.
    Calibrate {
        #[command(subcommand)]
        which: CalibrateCommand,
    },
    /// Turn an outside data set into a recording to replay:
    /// `nauta import broad TRIAL.csv.gz -o OUT.mcap`, `nauta import csv DIR -o OUT.mcap`.
    Import {
        #[command(subcommand)]
        which: ImportCommand,
    },
    /// Paper 004's post-mission smoother: the recording's LBL inputs through
    /// its LBL filter again, then the fixed-interval Rauch-Tung-Striebel
    /// backward pass; OUT is the recording plus the smoothed track
    /// `smoother/lbl/nav` (`nauta smooth run.mcap -o smoothed.mcap`).
    Smooth(smooth::command::SmoothArgs),
    /// LBL navigation: `nauta lbl plan LAYOUT -o MAP.png` maps paper 003's
    /// sensitivities and operating box of a transponder layout.
    Lbl {
        #[command(subcommand)]
        which: LblCommand,
    },
    /// Benchmarks (use a release build).
    Bench {
        #[command(subcommand)]
        which: BenchCommand,
    },
    /// Internal: the peer process of `nauta bench ipc`.
    #[command(hide = true, name = "__ipc-peer")]
    IpcPeer {
        /// Arguments passed by the benchmark driver.
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<String>,
    },
}

#[derive(Debug, Subcommand)]
enum CalibrateCommand {
    /// Hard and soft iron (paper 000 §IV-A): of a manifest's simulated
    /// magnetometer (a simulated manoeuvre at its site), or of a recorded
    /// manoeuvre (`--from FILE --field-ut F`).
    Magnetometer(calibrate::MagnetometerArgs),
}

#[derive(Debug, Subcommand)]
enum ImportCommand {
    /// A BROAD trial (IMU and optical reference) as `sensor/imu` and `sim/truth`,
    /// with a manifest that replays it through the attitude process.
    Broad(import::ImportBroadArgs),
    /// One trajectory of the Snapir AUV's A-KIT data set (github ansfl/A-KIT,
    /// `Data/TrajectoryN/`): its reference INS as the truth and the AHRS and
    /// depth, its DVL, and with `--imu` its 100 Hz IMU.
    Akit(import::akit::ImportAkitArgs),
    /// Any vehicle's log: `site.toml` and one CSV file per channel (`imu.csv`,
    /// `dvl.csv`, `ahrs.csv`, `depth.csv`, `gps.csv`, `modem.csv`, `lbl.csv`,
    /// `propeller.csv`, `truth.csv`; each optional; columns in the README),
    /// with a manifest that runs the estimators the channels allow.
    Csv(import::csv::ImportCsvArgs),
}

#[derive(Debug, Subcommand)]
enum LblCommand {
    /// Paper 003 §III for a transponder layout: the sensitivity of the
    /// position to range errors (Fig. 2) and to the baseline's length
    /// (Fig. 3) as level contours in MAP.png, and the desirable operating
    /// box (Fig. 4), drawn and printed.
    Plan(lbl_plan::command::PlanArgs),
}

#[derive(Debug, Subcommand)]
enum LogCommand {
    /// Channels, types, counts, rates, time span, gaps, metadata, events, and
    /// whether the file was cut short (and how much of it was read).
    Info(logcmd::InfoArgs),
}

#[derive(Debug, Subcommand)]
enum BenchCommand {
    /// Recording speed: a 45-minute survey written to MCAP and read back.
    Log {
        /// Print one JSON object instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Inter-process latency and throughput: iceoryx2 against a Unix socket and a pipe.
    Ipc {
        /// Print one JSON object instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Kill a random estimator every 5-15 s of a wall-clock survey at 10x; restarts,
    /// latencies, losses and the attitude error beside a run without kills.
    Chaos(bench::chaos::ChaosArgs),
    /// The aided INS's variants in process on the simulator: paper 002's
    /// manoeuvres over seeds (predicted against realised error), DVL spikes
    /// with and without the filter, the survey, speed.
    Nav(bench::nav::NavArgs),
    /// LBL navigation (paper 003's EKF) in process on the simulator over
    /// seeds, 2 and 4 transponders: accuracy, consistency, multipath, the
    /// current, a ten-minute blackout, figure of merit against round robin.
    Lbl(bench::lbl::LblArgs),
    /// Wall-clock pacing: the survey in `wall` clock at each `--rate` (1 and
    /// 10 by default); the sensor's wall span against the expected.
    Pacing(bench::pacing::PacingArgs),
    /// Attitude estimators in-process: BROAD real data (`--broad DIR`) with the BROAD
    /// metric, or paper 000's simulated conditions (`--sim`) and the PF's throughput.
    Attitude {
        /// A directory of BROAD-format trials (`.csv` or `.csv.gz`), e.g. ../shared/data/broad.
        #[arg(long, conflicts_with = "sim", required_unless_present = "sim")]
        broad: Option<std::path::PathBuf>,
        /// Paper 000's still, pitch-and-roll and yaw conditions on the simulator.
        #[arg(long)]
        sim: bool,
        /// Print one JSON object instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Paper 004's smoother (`nauta smooth`) on a 2-hour LBL mission: the
    /// forward and backward passes, and reading and writing the recording,
    /// timed apart.
    Smooth {
        /// Print one JSON object instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Simulator speed: the scenarios generated in-process, all sensors, one core.
    Sim {
        /// Print one JSON object instead of a table.
        #[arg(long)]
        json: bool,
    },
}

fn main() -> ExitCode {
    // Output piped into `head` and the like: end quietly when the reader
    // goes away, as Unix tools do, instead of panicking in `println!`.
    // SAFETY: restoring a signal's default disposition, before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    nauta_runtime::process::init_tracing();
    let cli = Cli::parse();
    match run(cli) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("nauta: error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> anyhow::Result<ExitCode> {
    match cli.command {
        Command::Launch(cmd) => launch::launch(&cmd).map(ExitCode::from),
        Command::Check(args) => launch::check(&args).map(|()| ExitCode::SUCCESS),
        Command::Status { json, namespace } => {
            pipeline::status(json, namespace.as_deref()).map(|()| ExitCode::SUCCESS)
        }
        Command::Stop { namespace } => pipeline::command(
            namespace.as_deref(),
            nauta_messages::pipeline_command::STOP,
            "",
            "",
        )
        .map(|()| ExitCode::SUCCESS),
        Command::Restart { process, namespace } => pipeline::command(
            namespace.as_deref(),
            nauta_messages::pipeline_command::RESTART,
            &process,
            "",
        )
        .map(|()| ExitCode::SUCCESS),
        Command::Swap {
            process,
            variant,
            namespace,
        } => pipeline::command(
            namespace.as_deref(),
            nauta_messages::pipeline_command::SWAP,
            &process,
            &variant,
        )
        .map(|()| ExitCode::SUCCESS),
        Command::Record(args) => logcmd::record(&args),
        Command::Replay(args) => logcmd::replay(&args),
        Command::Log { which } => match which {
            LogCommand::Info(args) => logcmd::info(&args),
        },
        Command::Eval(args) => eval::run(&args),
        Command::Export(args) => export::run(&args),
        Command::Report(args) => report::run(&args),
        Command::Calibrate { which } => match which {
            CalibrateCommand::Magnetometer(args) => calibrate::magnetometer(&args),
        },
        Command::Import { which } => match which {
            ImportCommand::Broad(args) => import::broad(&args),
            ImportCommand::Akit(args) => import::akit::akit(&args),
            ImportCommand::Csv(args) => import::csv::csv(&args),
        },
        Command::Smooth(args) => smooth::command::run(&args),
        Command::Lbl { which } => match which {
            LblCommand::Plan(args) => lbl_plan::command::run(&args),
        },
        Command::Bench { which } => match which {
            BenchCommand::Log { json } => bench::log::run(json).map(|()| ExitCode::SUCCESS),
            BenchCommand::Ipc { json } => bench::ipc::run(json).map(|()| ExitCode::SUCCESS),
            BenchCommand::Sim { json } => bench::sim::run(json).map(|()| ExitCode::SUCCESS),
            BenchCommand::Smooth { json } => bench::smooth::run(json).map(|()| ExitCode::SUCCESS),
            BenchCommand::Chaos(args) => bench::chaos::run(&args).map(|()| ExitCode::SUCCESS),
            BenchCommand::Pacing(args) => bench::pacing::run(&args).map(|()| ExitCode::SUCCESS),
            BenchCommand::Nav(args) => bench::nav::run_bench(&args).map(|()| ExitCode::SUCCESS),
            BenchCommand::Lbl(args) => bench::lbl::run_bench(&args).map(|()| ExitCode::SUCCESS),
            BenchCommand::Attitude { broad, sim, json } => match (broad, sim) {
                (Some(dir), _) => bench::attitude::run_broad(&dir, json),
                (None, _) => bench::attitude::run_sim(json),
            }
            .map(|()| ExitCode::SUCCESS),
        },
        Command::IpcPeer { args } => bench::ipc::peer(&args).map(|()| ExitCode::SUCCESS),
    }
}
