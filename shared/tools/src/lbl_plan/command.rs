//! `nauta lbl plan LAYOUT -o MAP.png [--json]`: the command line around
//! [`super::Plan`] and [`super::map`].

use std::io::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context as _;

use super::layout::Layout;
use super::{Plan, PlanOptions, map};

/// Arguments of `nauta lbl plan`.
#[derive(Debug, clap::Args)]
pub struct PlanArgs {
    /// The transponders: a manifest (its `[site]`'s transponders, or the
    /// layout a process's `lbl_layout` names, e.g. `launch/lbl.toml`), a CSV
    /// list (`.csv`: a header `id,north_m,east_m[,depth_m]`, then one
    /// transponder per line, metres north/east of the site's origin), or a
    /// `site.toml` of `nauta import csv` (its `[[transponders]]`).
    pub layout: PathBuf,
    /// The map to write (PNG): Figs. 2-3 as level contours with Fig. 4's box.
    #[arg(short = 'o', long = "output", value_name = "MAP.png")]
    pub output: PathBuf,
    /// The baseline whose operating box to plan, as two transponder ids
    /// (needed when the layout has more than two transponders).
    #[arg(long, value_name = "ID,ID")]
    pub pair: Option<String>,
    /// Where the vehicle starts, NORTH,EAST in metres (default 0,0: the
    /// site's origin); the box is on this side of the baseline.
    #[arg(long, value_name = "NORTH,EAST", allow_hyphen_values = true)]
    pub start: Option<String>,
    /// Print one JSON object (`{"baseline_m", "box": [[north_m, east_m], ...], ...}`).
    #[arg(long)]
    pub json: bool,
}

fn parse_pair(text: &str) -> anyhow::Result<[u32; 2]> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    let [a, b] = parts.as_slice() else {
        anyhow::bail!("--pair {text:?}: expected two transponder ids, ID,ID");
    };
    let id = |s: &str| {
        s.parse::<u32>()
            .with_context(|| format!("--pair {text:?}: {s:?} is not a transponder id"))
    };
    Ok([id(a)?, id(b)?])
}

fn parse_start(text: &str) -> anyhow::Result<[f64; 2]> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    let [n, e] = parts.as_slice() else {
        anyhow::bail!("--start {text:?}: expected NORTH,EAST in metres, e.g. 100,250");
    };
    let num = |s: &str, what: &str| {
        let v = s
            .parse::<f64>()
            .with_context(|| format!("--start {text:?}: {what} {s:?} is not a number"))?;
        anyhow::ensure!(
            v.abs() <= super::layout::MAX_COORDINATE_M,
            "--start {text:?}: {what} {v} is outside ±{} m",
            super::layout::MAX_COORDINATE_M
        );
        Ok(v)
    };
    Ok([num(n, "north")?, num(e, "east")?])
}

/// Whether the TOML file `path` is a manifest (it has `[run]` or
/// `[process.*]`) rather than the `site.toml` of an import.
fn is_manifest(path: &std::path::Path) -> anyhow::Result<bool> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let table: toml::Table = toml::from_str(&text)
        .map_err(|e| anyhow::anyhow!("{}: {}", path.display(), e.to_string().trim_end()))?;
    Ok(table.contains_key("run") || table.contains_key("process"))
}

/// The layout of `path`: a manifest (its site's transponders), a CSV list
/// (`.csv`), or the `site.toml` of `nauta import csv` (its
/// `[[transponders]]`). Every error names the file.
pub fn read_layout(path: &std::path::Path) -> anyhow::Result<Layout> {
    use super::layout::{LayoutError, Transponder};
    let named = |e: LayoutError| match e {
        // These name it already.
        LayoutError::Read { .. } | LayoutError::Csv { .. } => anyhow::Error::new(e),
        e => anyhow::Error::new(e).context(path.display().to_string()),
    };
    let is_csv = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"));
    if is_csv {
        return Layout::from_csv_file(path).map_err(named);
    }
    // (id, north, east, depth) of the manifest's site or the import's.
    let listed: Vec<(u32, f64, f64, f64)> = if is_manifest(path)? {
        let manifest = nauta_runtime::Manifest::load(path)?;
        let site = manifest.site.map(|s| s.transponders).unwrap_or_default();
        site.iter()
            .map(|t| (t.id, t.north_m, t.east_m, t.depth_m))
            .collect()
    } else {
        let site = crate::import::csv::site::CsvSite::read(path)?;
        site.transponders
            .iter()
            .map(|t| (t.id, t.north_m, t.east_m, t.depth_m))
            .collect()
    };
    let transponders = listed
        .into_iter()
        .map(|(id, north_m, east_m, depth_m)| Transponder {
            id,
            north_m,
            east_m,
            depth_m: Some(depth_m),
        })
        .collect();
    Layout::new(transponders).map_err(named)
}

/// Runs `nauta lbl plan`.
pub fn run(args: &PlanArgs) -> anyhow::Result<ExitCode> {
    let layout = read_layout(&args.layout)?;
    let options = PlanOptions {
        pair: args.pair.as_deref().map(parse_pair).transpose()?,
        start: args
            .start
            .as_deref()
            .map(parse_start)
            .transpose()?
            .unwrap_or(PlanOptions::default().start),
    };
    let plan = Plan::new(&layout, &options).with_context(|| args.layout.display().to_string())?;
    crate::part_file::write_via_part(&args.output, |part| map::draw(&plan, part))?;
    let text = if args.json {
        let mut v = plan.to_json();
        v["map"] = serde_json::json!(args.output.display().to_string());
        format!("{v}\n")
    } else {
        format!("{}map: {}\n", plan.text(), args.output.display())
    };
    match std::io::stdout().lock().write_all(text.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
            Err(anyhow::Error::new(e).context("cannot write to stdout"))
        }
        _ => Ok(ExitCode::SUCCESS),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pairs_and_starts_parse_with_clear_errors() {
        assert_eq!(parse_pair("1, 2").expect("pair"), [1, 2]);
        assert_eq!(parse_start("-50,150.5").expect("start"), [-50.0, 150.5]);
        for bad in ["1", "1,2,3", "a,2", "-1,2"] {
            assert!(parse_pair(bad).is_err(), "{bad}");
        }
        for bad in ["1", "x,2", "nan,0", "1e9,0"] {
            assert!(parse_start(bad).is_err(), "{bad}");
        }
    }
}
