//! `nauta report FILE -o DIR`: PNG plots of a recording and an `index.html`
//! that shows them with the eval table (DESIGN §9). The figures come from
//! [`crate::eval::evaluate`], the computation `nauta eval` prints.

pub(crate) mod font;
mod plots;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Context as _;

use crate::eval::{self, Evaluation, Reference};
use plots::Plot;

/// Arguments of `nauta report`.
#[derive(Debug, clap::Args)]
pub struct ReportArgs {
    /// The recording (MCAP).
    pub file: PathBuf,
    /// Directory to write the plots (PNG) and index.html to (created if
    /// needed; files of the same names are replaced).
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
}

/// Runs `nauta report`.
pub fn run(args: &ReportArgs) -> anyhow::Result<ExitCode> {
    // Before the long read: a machine without a font fails at once.
    font::register()?;
    let data = eval::read(&args.file)?;
    let evaluation = eval::evaluate(&args.file, &data)?;
    let notes = eval::notes(&data, &evaluation);
    for n in &notes {
        eprintln!("nauta report: {n}");
    }
    std::fs::create_dir_all(&args.output)
        .with_context(|| format!("cannot create {}", args.output.display()))?;
    let plots = plots::all(&data, &evaluation, &args.output)?;
    let index = args.output.join("index.html");
    std::fs::write(&index, html(&evaluation, &plots, &notes))
        .with_context(|| format!("cannot write {}", index.display()))?;
    println!(
        "{}: {} plots and {}",
        args.output.display(),
        plots.len(),
        index.display()
    );
    for p in &plots {
        println!("  {}", Path::new(&args.output).join(p.file).display());
    }
    Ok(ExitCode::SUCCESS)
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The index page: the eval table, the notes, every plot.
fn html(eval: &Evaluation, plots: &[Plot], notes: &[String]) -> String {
    let title = format!("nauta report: {}", escape(&eval.file));
    let against = match eval.reference {
        Reference::Truth => "the simulator's truth (<code>sim/truth</code>)",
        Reference::Gps => "the surface GPS fixes (<code>sensor/gps</code>)",
    };
    let mut h = String::new();
    let _ = write!(
        h,
        r#"<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>{title}</title>
<style>
body {{ font-family: sans-serif; margin: 2em; color: #222; }}
table {{ border-collapse: collapse; margin: 1em 0; }}
th, td {{ border: 1px solid #bbb; padding: 0.25em 0.7em; }}
td {{ text-align: right; font-variant-numeric: tabular-nums; }}
th {{ background: #eee; }} td.label {{ text-align: left; }}
figure {{ margin: 2em 0; }} img {{ max-width: 100%; border: 1px solid #ddd; }}
figcaption {{ max-width: 70em; }}
</style>
</head>
<body>
<h1>{title}</h1>
<p>Every estimate stream against {against}. Keys and definitions: README, "Evaluating a recording".</p>
<table>
<tr><th></th>"#
    );
    for topic in eval.streams.keys() {
        let _ = write!(h, "<th>{}</th>", escape(topic));
    }
    h.push_str("</tr>\n");
    for (label, get) in eval::ROWS {
        let cells: Vec<Option<String>> = eval.streams.values().map(get).collect();
        if cells.iter().all(Option::is_none) {
            continue;
        }
        let _ = write!(h, "<tr><td class=\"label\">{}</td>", escape(label));
        for c in cells {
            let _ = write!(h, "<td>{}</td>", escape(c.as_deref().unwrap_or("-")));
        }
        h.push_str("</tr>\n");
    }
    h.push_str("</table>\n");
    if !notes.is_empty() {
        h.push_str("<ul>\n");
        for n in notes {
            let _ = writeln!(h, "<li>{}</li>", escape(n));
        }
        h.push_str("</ul>\n");
    }
    for p in plots {
        let _ = write!(
            h,
            "<figure>\n<h2>{}</h2>\n<img src=\"{}\" alt=\"{}\">\n<figcaption>{}</figcaption>\n</figure>\n",
            escape(&p.title),
            escape(p.file),
            escape(&p.title),
            escape(&p.caption)
        );
    }
    h.push_str("</body>\n</html>\n");
    h
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::Metrics;

    #[test]
    fn the_index_shows_the_table_and_every_plot_escaped() {
        let mut streams = std::collections::BTreeMap::new();
        streams.insert(
            "ains/nav".to_owned(),
            Metrics {
                samples: 3,
                north_rms_m: Some(1.25),
                ..Default::default()
            },
        );
        let eval = Evaluation {
            file: "a<b>.mcap".into(),
            reference: Reference::Gps,
            streams,
            skipped: Default::default(),
            series: Default::default(),
        };
        let plots = [Plot {
            file: "trajectory.png",
            title: "Trajectory".into(),
            caption: "x & y".into(),
        }];
        let h = html(&eval, &plots, &["a note".into()]);
        assert!(h.contains("a&lt;b&gt;.mcap") && !h.contains("a<b>"), "{h}");
        assert!(
            h.contains("<td>1.250</td>") && h.contains("<th>ains/nav</th>"),
            "{h}"
        );
        // Rows that apply to no stream are left out.
        assert!(!h.contains("down RMS"), "{h}");
        assert!(
            h.contains("<img src=\"trajectory.png\"") && h.contains("x &amp; y"),
            "{h}"
        );
        assert!(h.contains("<li>a note</li>"), "{h}");
    }
}
