//! The report's PNG plots (plotters, bitmap backend). Each plot is drawn only
//! when the recording has its data; each returns what `index.html` says
//! about it.

use std::path::Path;

use nalgebra::{Matrix2, Vector3};
use nauta_log::run::GeoOrigin;
use plotters::coord::Shift;
use plotters::prelude::*;

use super::font::FAMILY;
use crate::eval::Evaluation;
use crate::eval::compute::{self, CHI2_2DOF_95, Reference};
use crate::eval::data::{Data, Horizontal, Stream};

/// A plot written to the report directory.
#[derive(Debug, Clone)]
pub struct Plot {
    /// File name in the directory.
    pub file: &'static str,
    /// Heading.
    pub title: String,
    /// What it shows.
    pub caption: String,
}

const WIDTH: u32 = 1100;
const PANEL_HEIGHT: u32 = 300;
/// Points drawn per series at most (longer series are decimated evenly).
const MAX_POINTS: usize = 4000;
/// Uncertainty ellipses drawn per stream on the trajectory, about.
const ELLIPSES_PER_STREAM: f64 = 20.0;

fn err(e: impl std::fmt::Display) -> anyhow::Error {
    anyhow::anyhow!("cannot draw the plot: {e}")
}

fn color(i: usize) -> RGBColor {
    const P: [RGBColor; 8] = [
        RGBColor(31, 119, 180),
        RGBColor(255, 127, 14),
        RGBColor(44, 160, 44),
        RGBColor(214, 39, 40),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(227, 119, 194),
        RGBColor(23, 190, 207),
    ];
    P[i % P.len()]
}

/// Every k-th item so that at most `max` remain, and the last.
fn decimate<T: Copy>(v: &[T], max: usize) -> Vec<T> {
    if v.len() <= max {
        return v.to_vec();
    }
    let k = v.len().div_ceil(max);
    let mut out: Vec<T> = v.iter().step_by(k).copied().collect();
    if !(v.len() - 1).is_multiple_of(k)
        && let Some(last) = v.last()
    {
        out.push(*last);
    }
    out
}

/// `[min, max]` of finite values with 5% padding (±1 around a single value).
fn range(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if lo > hi {
        return None;
    }
    if hi - lo < 1e-9 {
        return Some((lo - 1.0, hi + 1.0));
    }
    let pad = 0.05 * (hi - lo);
    Some((lo - pad, hi + pad))
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Style {
    Line,
    Dots,
    Crosses,
}

#[derive(Debug, Clone)]
struct Series {
    label: String,
    color: RGBColor,
    style: Style,
    points: Vec<(f64, f64)>,
}

#[derive(Debug, Clone)]
struct Panel {
    title: String,
    y_desc: String,
    series: Vec<Series>,
    /// Its own time span (a detail), else the span shared by the panels.
    x: Option<(f64, f64)>,
}

impl Panel {
    fn new(title: impl Into<String>, y_desc: impl Into<String>) -> Self {
        Panel {
            title: title.into(),
            y_desc: y_desc.into(),
            series: Vec::new(),
            x: None,
        }
    }

    fn push(
        &mut self,
        label: impl Into<String>,
        color: RGBColor,
        style: Style,
        points: Vec<(f64, f64)>,
    ) {
        if !points.is_empty() {
            self.series.push(Series {
                label: label.into(),
                color,
                style,
                points: decimate(&points, MAX_POINTS),
            });
        }
    }
}

/// Panels stacked vertically, time (s) on every x axis.
fn draw_panels(path: &Path, panels: &[Panel]) -> anyhow::Result<()> {
    let panels: Vec<&Panel> = panels.iter().filter(|p| !p.series.is_empty()).collect();
    let height = PANEL_HEIGHT * panels.len().max(1) as u32;
    let root = BitMapBackend::new(path, (WIDTH, height)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let x = range(
        panels
            .iter()
            .filter(|p| p.x.is_none())
            .flat_map(|p| p.series.iter().flat_map(|s| s.points.iter().map(|p| p.0))),
    )
    .unwrap_or((0.0, 1.0));
    for (area, p) in root
        .split_evenly((panels.len().max(1), 1))
        .iter()
        .zip(&panels)
    {
        let x = p.x.unwrap_or(x);
        let inside = |q: &&(f64, f64)| q.0 >= x.0 && q.0 <= x.1;
        let y = range(
            p.series
                .iter()
                .flat_map(|s| s.points.iter().filter(inside).map(|q| q.1)),
        )
        .unwrap_or((-1.0, 1.0));
        draw_panel(area, p, x, y)?;
    }
    root.present().map_err(err)
}

fn draw_panel(
    area: &DrawingArea<BitMapBackend<'_>, Shift>,
    p: &Panel,
    x: (f64, f64),
    y: (f64, f64),
) -> anyhow::Result<()> {
    let mut chart = ChartBuilder::on(area)
        .caption(&p.title, (FAMILY, 17))
        .margin(8)
        .x_label_area_size(34)
        .y_label_area_size(70)
        .build_cartesian_2d(x.0..x.1, y.0..y.1)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("time (s)")
        .y_desc(p.y_desc.as_str())
        .label_style((FAMILY, 12))
        .axis_desc_style((FAMILY, 13))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(err)?;
    for s in &p.series {
        let c = s.color;
        let pts = s
            .points
            .iter()
            .copied()
            .filter(|q| q.0 >= x.0 && q.0 <= x.1);
        let anno = match s.style {
            Style::Line => chart.draw_series(LineSeries::new(pts, c.stroke_width(1))),
            Style::Dots => chart.draw_series(pts.map(|q| Circle::new(q, 2, c.filled()))),
            Style::Crosses => chart.draw_series(pts.map(|q| Cross::new(q, 3, c.stroke_width(1)))),
        }
        .map_err(err)?;
        anno.label(s.label.as_str())
            .legend(move |(x, y)| Rectangle::new([(x, y - 4), (x + 14, y + 4)], c.filled()));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font((FAMILY, 12))
        .draw()
        .map_err(err)?;
    Ok(())
}

/// Every plot whose data the recording has.
pub fn all(data: &Data, eval: &Evaluation, dir: &Path) -> anyhow::Result<Vec<Plot>> {
    let frame = compute::local_frame(data).ok().map(|f| f.0);
    let mut plots = Vec::new();
    plots.extend(trajectory(data, eval, frame, dir)?);
    plots.extend(position_error(data, eval, dir)?);
    plots.extend(ellipse_axes(data, dir)?);
    plots.extend(range_residuals(data, frame, dir)?);
    plots.extend(attitude_error(data, eval, dir)?);
    Ok(plots)
}

/// Topics that were evaluated, each with its colour.
fn evaluated<'a>(data: &'a Data, eval: &Evaluation) -> Vec<(usize, &'a Stream)> {
    data.streams
        .values()
        .enumerate()
        .filter(|(_, s)| eval.series.contains_key(&s.topic))
        .collect()
}

// ---------------------------------------------------------------------------
// Trajectory
// ---------------------------------------------------------------------------

/// Local (north, east) of a horizontal position in the plot's frame.
fn local(origin: &GeoOrigin, frame: Option<GeoOrigin>, p: Horizontal) -> Option<(f64, f64)> {
    match p {
        Horizontal::Geodetic { lat_rad, lon_rad } => Some(origin.to_local(lat_rad, lon_rad)),
        Horizontal::Local { north_m, east_m } => {
            let f = frame?;
            let (lat, lon) = f.to_geodetic(north_m, east_m);
            Some(origin.to_local(lat, lon))
        }
    }
}

/// The 95% ellipse of `cov` around (north, east), as (east, north) points.
fn ellipse(center: (f64, f64), cov: &Matrix2<f64>) -> Vec<(f64, f64)> {
    let (a, b) = compute::ellipse_axes(cov);
    let k = CHI2_2DOF_95.sqrt();
    let (a, b) = (k * a, k * b);
    let phi = compute::ellipse_orientation(cov);
    let (s, c) = phi.sin_cos();
    (0..=48)
        .map(|i| {
            let t = std::f64::consts::TAU * i as f64 / 48.0;
            let (u, v) = (a * t.cos(), b * t.sin());
            let n = center.0 + u * c - v * s;
            let e = center.1 + u * s + v * c;
            (e, n)
        })
        .collect()
}

fn trajectory(
    data: &Data,
    eval: &Evaluation,
    frame: Option<GeoOrigin>,
    dir: &Path,
) -> anyhow::Result<Option<Plot>> {
    let origin = frame
        .or_else(|| {
            data.truth.first().map(|t| GeoOrigin {
                lat_rad: t.lat_rad,
                lon_rad: t.lon_rad,
            })
        })
        .or_else(|| {
            data.gps.first().map(|g| GeoOrigin {
                lat_rad: g.lat_rad,
                lon_rad: g.lon_rad,
            })
        });
    let Some(origin) = origin else {
        return Ok(None);
    };
    // (east, north) everywhere below: x east, y north.
    let truth: Vec<(f64, f64)> = data
        .truth
        .iter()
        .map(|t| origin.to_local(t.lat_rad, t.lon_rad))
        .map(|(n, e)| (e, n))
        .collect();
    let gps: Vec<(f64, f64)> = data
        .gps
        .iter()
        .map(|g| origin.to_local(g.lat_rad, g.lon_rad))
        .map(|(n, e)| (e, n))
        .collect();
    let mut tracks = Vec::new();
    let mut ellipses: Vec<(RGBColor, Vec<(f64, f64)>)> = Vec::new();
    for (i, s) in evaluated(data, eval) {
        if !s.kind.has_position() {
            continue;
        }
        let pts: Vec<(f64, f64)> = s
            .samples
            .iter()
            .filter_map(|x| x.pos.and_then(|p| local(&origin, frame, p)))
            .map(|(n, e)| (e, n))
            .collect();
        if pts.is_empty() {
            continue;
        }
        let with_cov: Vec<_> = s.samples.iter().filter(|x| x.cov_ne_m2.is_some()).collect();
        if let (Some(a), Some(b)) = (with_cov.first(), with_cov.last()) {
            let every_ns = ((b.stamp_ns - a.stamp_ns) as f64 / ELLIPSES_PER_STREAM).max(1e9) as u64;
            let mut next = a.stamp_ns;
            for x in with_cov {
                if x.stamp_ns < next {
                    continue;
                }
                next = x.stamp_ns + every_ns;
                if let (Some(c), Some(cov)) =
                    (x.pos.and_then(|p| local(&origin, frame, p)), x.cov_ne_m2)
                {
                    ellipses.push((color(i), ellipse(c, &cov)));
                }
            }
        }
        tracks.push((s.topic.clone(), color(i), decimate(&pts, MAX_POINTS)));
    }
    let transponders: Vec<(u32, (f64, f64))> = match frame {
        Some(f) => data
            .run
            .transponders
            .iter()
            .map(|t| {
                let (lat, lon) = f.to_geodetic(t.north_m, t.east_m);
                let (n, e) = origin.to_local(lat, lon);
                (t.id, (e, n))
            })
            .collect(),
        None => Vec::new(),
    };
    let buoy: Vec<(f64, f64)> = data
        .buoy
        .iter()
        .map(|b| origin.to_local(b.lat_rad, b.lon_rad))
        .map(|(n, e)| (e, n))
        .collect();
    if truth.is_empty() && tracks.is_empty() && gps.is_empty() {
        return Ok(None);
    }

    let all = truth
        .iter()
        .chain(&gps)
        .chain(tracks.iter().flat_map(|t| t.2.iter()))
        .chain(transponders.iter().map(|t| &t.1))
        .chain(&buoy);
    let (mut x0, mut x1) = range(all.clone().map(|p| p.0)).unwrap_or((-1.0, 1.0));
    let (mut y0, mut y1) = range(all.map(|p| p.1)).unwrap_or((-1.0, 1.0));
    // Same scale on both axes: widen the narrower range.
    let (w, h) = (WIDTH, 900u32);
    let (pw, ph) = (f64::from(w - 100), f64::from(h - 90));
    let scale = ((x1 - x0) / pw).max((y1 - y0) / ph);
    let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
    (x0, x1) = (cx - 0.5 * scale * pw, cx + 0.5 * scale * pw);
    (y0, y1) = (cy - 0.5 * scale * ph, cy + 0.5 * scale * ph);

    let path = dir.join("trajectory.png");
    let root = BitMapBackend::new(&path, (w, h)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let mut chart = ChartBuilder::on(&root)
        .caption("Trajectory (north/east from the origin)", (FAMILY, 18))
        .margin(10)
        .x_label_area_size(36)
        .y_label_area_size(64)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("east (m)")
        .y_desc("north (m)")
        .label_style((FAMILY, 12))
        .axis_desc_style((FAMILY, 13))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(err)?;
    if !truth.is_empty() {
        chart
            .draw_series(LineSeries::new(
                decimate(&truth, MAX_POINTS),
                BLACK.stroke_width(2),
            ))
            .map_err(err)?
            .label("truth")
            .legend(|(x, y)| Rectangle::new([(x, y - 4), (x + 14, y + 4)], BLACK.filled()));
    }
    if !gps.is_empty() {
        let grey = RGBColor(120, 120, 120);
        chart
            .draw_series(gps.iter().map(|p| Circle::new(*p, 2, grey.filled())))
            .map_err(err)?
            .label("GPS fixes")
            .legend(move |(x, y)| Circle::new((x + 7, y), 3, grey.filled()));
    }
    for (topic, c, pts) in &tracks {
        let c = *c;
        chart
            .draw_series(LineSeries::new(pts.iter().copied(), c.stroke_width(1)))
            .map_err(err)?
            .label(topic.as_str())
            .legend(move |(x, y)| Rectangle::new([(x, y - 4), (x + 14, y + 4)], c.filled()));
    }
    for (c, pts) in &ellipses {
        chart
            .draw_series(std::iter::once(PathElement::new(
                pts.clone(),
                c.stroke_width(1),
            )))
            .map_err(err)?;
    }
    if !buoy.is_empty() {
        let c = RGBColor(0, 150, 150);
        chart
            .draw_series(buoy.iter().map(|p| Cross::new(*p, 4, c.stroke_width(2))))
            .map_err(err)?
            .label("buoy (modem)")
            .legend(move |(x, y)| Cross::new((x + 7, y), 4, c.stroke_width(2)));
    }
    if !transponders.is_empty() {
        let c = RGBColor(200, 0, 0);
        chart
            .draw_series(
                transponders
                    .iter()
                    .map(|(_, p)| TriangleMarker::new(*p, 7, c.filled())),
            )
            .map_err(err)?
            .label("LBL transponders")
            .legend(move |(x, y)| TriangleMarker::new((x + 7, y), 5, c.filled()));
        chart
            .draw_series(transponders.iter().map(|(id, p)| {
                Text::new(format!("  T{id}"), *p, (FAMILY, 13).into_font().color(&c))
            }))
            .map_err(err)?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font((FAMILY, 12))
        .draw()
        .map_err(err)?;
    root.present().map_err(err)?;
    let mut caption = String::from(
        "Estimated tracks against the truth, in metres north and east of the origin (the run's declared origin, else the start), same scale on both axes.",
    );
    if !ellipses.is_empty() {
        caption += " Ellipses: the 95% uncertainty region of the published position covariance (chi-square, 2 dof), to scale, at regular intervals.";
    }
    if !transponders.is_empty() {
        caption += " Triangles: LBL transponders (from the run's metadata).";
    }
    if !buoy.is_empty() {
        caption += " Crosses: buoy positions broadcast over the modem.";
    }
    Ok(Some(Plot {
        file: "trajectory.png",
        title: "Trajectory".into(),
        caption,
    }))
}

// ---------------------------------------------------------------------------
// Errors against time
// ---------------------------------------------------------------------------

fn position_error(data: &Data, eval: &Evaluation, dir: &Path) -> anyhow::Result<Option<Plot>> {
    let style = match eval.reference {
        Reference::Truth => Style::Line,
        Reference::Gps => Style::Dots,
    };
    let mut north = Panel::new("North error", "north (m)");
    let mut east = Panel::new("East error", "east (m)");
    let mut down = Panel::new("Down error", "down (m)");
    let mut horizontal = Panel::new("Horizontal error", "horizontal (m)");
    for (i, s) in evaluated(data, eval) {
        let errors = &eval.series[&s.topic];
        let ne: Vec<(f64, [f64; 2])> = errors
            .iter()
            .filter_map(|e| e.ne_m.map(|v| (data.t_s(e.stamp_ns), v)))
            .collect();
        north.push(
            &s.topic,
            color(i),
            style,
            ne.iter().map(|(t, v)| (*t, v[0])).collect(),
        );
        east.push(
            &s.topic,
            color(i),
            style,
            ne.iter().map(|(t, v)| (*t, v[1])).collect(),
        );
        horizontal.push(
            &s.topic,
            color(i),
            style,
            ne.iter().map(|(t, v)| (*t, v[0].hypot(v[1]))).collect(),
        );
        down.push(
            &s.topic,
            color(i),
            style,
            errors
                .iter()
                .filter_map(|e| e.down_m.map(|d| (data.t_s(e.stamp_ns), d)))
                .collect(),
        );
    }
    if horizontal.series.is_empty() {
        return Ok(None);
    }
    draw_panels(
        &dir.join("position_error.png"),
        &[north, east, down, horizontal],
    )?;
    let against = match eval.reference {
        Reference::Truth => "the truth",
        Reference::Gps => "the GPS fixes (one point per fix)",
    };
    Ok(Some(Plot {
        file: "position_error.png",
        title: "Position error".into(),
        caption: format!(
            "Estimate minus {against}, per stream, against time since the start of the recording."
        ),
    }))
}

fn attitude_error(data: &Data, eval: &Evaluation, dir: &Path) -> anyhow::Result<Option<Plot>> {
    let mut panels = [
        Panel::new("Roll error", "roll (deg)"),
        Panel::new("Pitch error", "pitch (deg)"),
        Panel::new("Yaw error (wrapped to ±180°)", "yaw (deg)"),
    ];
    for (i, s) in evaluated(data, eval) {
        let att: Vec<(f64, [f64; 3])> = eval.series[&s.topic]
            .iter()
            .filter_map(|e| {
                e.attitude.map(|a| {
                    (
                        data.t_s(e.stamp_ns),
                        [a.roll_rad, a.pitch_rad, a.yaw_rad].map(f64::to_degrees),
                    )
                })
            })
            .collect();
        for (k, p) in panels.iter_mut().enumerate() {
            p.push(
                &s.topic,
                color(i),
                Style::Line,
                att.iter().map(|(t, v)| (*t, v[k])).collect(),
            );
        }
    }
    if panels[0].series.is_empty() {
        return Ok(None);
    }
    draw_panels(&dir.join("attitude_error.png"), &panels)?;
    Ok(Some(Plot {
        file: "attitude_error.png",
        title: "Attitude error".into(),
        caption: "Roll, pitch and yaw of the estimate minus those of the truth (ZYX Euler angles), per stream."
            .into(),
    }))
}

// ---------------------------------------------------------------------------
// Uncertainty ellipse axes (paper 004 Figs. 6-8)
// ---------------------------------------------------------------------------

fn ellipse_axes(data: &Data, dir: &Path) -> anyhow::Result<Option<Plot>> {
    let mut panels = Vec::new();
    let mut majors = Panel::new(
        "Semi-major axes compared (as paper 004 Fig. 8)",
        "semi-major (m)",
    );
    for (i, s) in data.streams.values().enumerate() {
        let axes: Vec<(f64, (f64, f64))> = s
            .samples
            .iter()
            .filter_map(|x| {
                x.cov_ne_m2
                    .map(|c| (data.t_s(x.stamp_ns), compute::ellipse_axes(&c)))
            })
            .collect();
        if axes.is_empty() {
            continue;
        }
        let mut p = Panel::new(
            format!("{}: uncertainty ellipse semi-axes (1σ)", s.topic),
            "semi-axis (m)",
        );
        p.push(
            "semi-major",
            color(i),
            Style::Line,
            axes.iter().map(|(t, a)| (*t, a.0)).collect(),
        );
        p.push(
            "semi-minor",
            RGBColor(110, 110, 110),
            Style::Line,
            axes.iter().map(|(t, a)| (*t, a.1)).collect(),
        );
        majors.push(
            &s.topic,
            color(i),
            Style::Line,
            axes.iter().map(|(t, a)| (*t, a.0)).collect(),
        );
        panels.push(p);
    }
    if panels.is_empty() {
        return Ok(None);
    }
    let compared = majors.series.len() >= 2;
    let detail = compared.then(|| detail_window(&majors)).flatten();
    if compared {
        if let Some((t0, t1)) = detail {
            // Paper 004 Fig. 8 shows "a short period of the mission": the
            // saw teeth of the real-time filter against the smoothed curve.
            let mut d = majors.clone();
            d.title = format!(
                "Semi-major axes, detail from {t0:.0} s to {t1:.0} s (as paper 004 Fig. 8)"
            );
            d.series = majors
                .series
                .iter()
                .map(|s| Series {
                    points: full_rate(data, &s.label, t0, t1).unwrap_or_else(|| s.points.clone()),
                    ..s.clone()
                })
                .collect();
            d.x = Some((t0, t1));
            panels.push(majors);
            panels.push(d);
        } else {
            panels.push(majors);
        }
    }
    draw_panels(&dir.join("ellipse_axes.png"), &panels)?;
    let mut caption = String::from(
        "Lengths of the semi-axes of the 1σ position uncertainty ellipse (square roots of the eigenvalues of the published north/east covariance; for lbl/nav the x-y block P_xy of P), against time, as papers 003 Fig. 6 and 004 Figs. 6-7.",
    );
    if compared {
        caption += " Then the semi-major axes of every stream together (paper 004 Fig. 8: real time against smoothed)";
        caption += if detail.is_some() {
            ", and a detail of two minutes in the middle of the mission at full rate."
        } else {
            "."
        };
    }
    Ok(Some(Plot {
        file: "ellipse_axes.png",
        title: "Uncertainty ellipse axes".into(),
        caption,
    }))
}

/// Two minutes in the middle of the span of `p`'s series (the whole span
/// when shorter), when a smoothed track (`smoother/...`) is among them.
fn detail_window(p: &Panel) -> Option<(f64, f64)> {
    const DETAIL_S: f64 = 120.0;
    if !p.series.iter().any(|s| s.label.starts_with("smoother/")) {
        return None;
    }
    let (t0, t1) = range(p.series.iter().flat_map(|s| s.points.iter().map(|q| q.0)))?;
    let mid = 0.5 * (t0 + t1);
    Some((
        (mid - 0.5 * DETAIL_S).max(t0),
        (mid + 0.5 * DETAIL_S).min(t1),
    ))
}

/// The semi-major axes of stream `topic` between `t0` and `t1` s, every
/// sample (the panels of the whole mission are decimated).
fn full_rate(data: &Data, topic: &str, t0: f64, t1: f64) -> Option<Vec<(f64, f64)>> {
    let s = data.streams.values().find(|s| s.topic == topic)?;
    Some(
        s.samples
            .iter()
            .filter_map(|x| {
                let t = data.t_s(x.stamp_ns);
                (t >= t0 && t <= t1)
                    .then(|| x.cov_ne_m2.map(|c| (t, compute::ellipse_axes(&c).0)))
                    .flatten()
            })
            .collect(),
    )
}

// ---------------------------------------------------------------------------
// LBL range residuals (paper 003 Fig. 7)
// ---------------------------------------------------------------------------

/// 3-D distance from the truth at `stamp` to a transponder, m.
fn true_range(data: &Data, frame: &GeoOrigin, stamp: u64, tx: &Vector3<f64>) -> Option<f64> {
    let t = compute::truth_at(&data.truth, stamp)?;
    let (n, e) = frame.to_local(t.lat_rad, t.lon_rad);
    Some((Vector3::new(n, e, t.depth_m) - tx).norm())
}

fn range_residuals(
    data: &Data,
    frame: Option<GeoOrigin>,
    dir: &Path,
) -> anyhow::Result<Option<Plot>> {
    let mut panels = Vec::new();
    let mut caption = Vec::new();
    // A smoothed track carries the filter's last innovation unchanged (the
    // smoother computes none): its panel would repeat the filter's.
    for s in data
        .streams
        .values()
        .filter(|s| !s.topic.starts_with("smoother/"))
    {
        let mut last = None;
        let mut by_id: std::collections::BTreeMap<u32, Vec<(f64, f64)>> = Default::default();
        let mut rejected = Vec::new();
        for x in &s.samples {
            let Some(inn) = x.innovation else { continue };
            // The filter repeats its last innovation until the next range.
            if last == Some(inn) {
                continue;
            }
            last = Some(inn);
            let p = (data.t_s(x.stamp_ns), inn.residual_m);
            if inn.accepted {
                by_id.entry(inn.transponder_id).or_default().push(p);
            } else {
                rejected.push(p);
            }
        }
        if by_id.is_empty() && rejected.is_empty() {
            continue;
        }
        let mut p = Panel::new(
            format!("{}: measured minus predicted range, r - r*", s.topic),
            "residual (m)",
        );
        for (k, (id, pts)) in by_id.into_iter().enumerate() {
            p.push(format!("T{id}"), color(k), Style::Dots, pts);
        }
        p.push(
            "rejected (gate)",
            RGBColor(200, 0, 0),
            Style::Crosses,
            rejected,
        );
        panels.push(p);
        caption.push(format!(
            "{}: the innovation r - r* of each range the filter processed (paper 003 §V-C), accepted by transponder, rejected by the Mahalanobis gate as crosses.",
            s.topic
        ));
    }
    // sensor/lbl against the truth: c (t_rt - t_ta) / 2 against the mean of the
    // outbound range (vehicle at the interrogation) and the return range
    // (vehicle at the reply), as the simulator forms the round trip.
    let acoustics = (
        frame,
        data.run.sound_speed_m_s,
        data.run.turnaround_s,
        data.truth.is_empty(),
    );
    if !data.lbl_replies.is_empty()
        && let (Some(frame), Some(c), Some(t_ta), false) = acoustics
        && !data.run.transponders.is_empty()
    {
        let mut by_id: std::collections::BTreeMap<u32, Vec<(f64, f64)>> = Default::default();
        for r in &data.lbl_replies {
            let Some(tx) = data
                .run
                .transponders
                .iter()
                .find(|t| t.id == r.transponder_id && t.depth_m.is_finite())
            else {
                continue;
            };
            // A transponder's own turnaround, when the site gives one.
            let t_ta = tx.turnaround_s.unwrap_or(t_ta);
            let txv = Vector3::new(tx.north_m, tx.east_m, tx.depth_m);
            let (Some(d_out), Some(d_back)) = (
                true_range(data, &frame, r.interrogation_ns, &txv),
                true_range(data, &frame, r.stamp_ns, &txv),
            ) else {
                continue;
            };
            let measured = 0.5 * c * (r.round_trip_s - t_ta);
            by_id
                .entry(r.transponder_id)
                .or_default()
                .push((data.t_s(r.stamp_ns), measured - 0.5 * (d_out + d_back)));
        }
        if !by_id.is_empty() {
            let mut p = Panel::new("sensor/lbl: measured minus true range", "residual (m)");
            for (k, (id, pts)) in by_id.into_iter().enumerate() {
                p.push(format!("T{id}"), color(k), Style::Dots, pts);
            }
            panels.push(p);
            caption.push(format!(
                "sensor/lbl: each reply's range c (t_rt - t_ta) / 2 (c = {c:.2} m/s, t_ta = {:.1} ms, from the run's metadata) minus the true range, the mean of the outbound and return legs: clock quantisation, and multipath replies as outliers.",
                t_ta * 1e3
            ));
        }
    }
    if panels.is_empty() {
        return Ok(None);
    }
    draw_panels(&dir.join("range_residuals.png"), &panels)?;
    Ok(Some(Plot {
        file: "range_residuals.png",
        title: "LBL range residuals (as paper 003 Fig. 7)".into(),
        caption: caption.join(" "),
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimation_keeps_the_ends_and_the_bound() {
        let v: Vec<usize> = (0..10_001).collect();
        let d = decimate(&v, 4000);
        assert!(d.len() <= 4001, "{}", d.len());
        assert_eq!((d[0], *d.last().expect("last")), (0, 10_000));
        assert_eq!(decimate(&v[..5], 10), v[..5]);
    }

    #[test]
    fn ranges_pad_and_survive_degenerate_data() {
        assert_eq!(range([1.0, 1.0].into_iter()), Some((0.0, 2.0)));
        assert_eq!(range([f64::NAN].into_iter()), None);
        let (lo, hi) = range([0.0, 10.0, f64::INFINITY].into_iter()).expect("range");
        assert!((lo + 0.5).abs() < 1e-12 && (hi - 10.5).abs() < 1e-12);
    }

    #[test]
    fn the_95_ellipse_has_the_chi_square_axes() {
        let pts = ellipse((10.0, 20.0), &Matrix2::new(4.0, 0.0, 0.0, 1.0));
        let k = CHI2_2DOF_95.sqrt();
        // (east, north): t = 0 is the major (north) axis.
        assert!((pts[0].0 - 20.0).abs() < 1e-12 && (pts[0].1 - (10.0 + 2.0 * k)).abs() < 1e-12);
        assert!(pts.iter().all(|p| {
            let (dn, de) = (p.1 - 10.0, p.0 - 20.0);
            (dn * dn / 4.0 + de * de - CHI2_2DOF_95).abs() < 1e-9
        }));
    }
}
