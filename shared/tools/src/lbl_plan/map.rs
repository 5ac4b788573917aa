//! The plan's PNG: paper 003 Fig. 2 (left) and Fig. 3 (right) as filled
//! level bands with contour lines over the area, each with the transponders,
//! the baseline, the start and Fig. 4's box.

use std::path::Path;

use plotters::prelude::*;

use super::Plan;
use super::contour::Grid;
use super::layout::Transponder;
use super::sensitivity::{baseline_sensitivity, range_sensitivity};
use super::{BASELINE_LEVELS, RANGE_LEVELS};
use crate::report::font::{self, FAMILY};

/// Samples per side of each map.
const SAMPLES: usize = 181;
/// Pixels: width of each panel, and the height.
const PANEL: u32 = 800;
const HEIGHT: u32 = 880;

fn err(e: impl std::fmt::Display) -> anyhow::Error {
    anyhow::anyhow!("cannot draw the map: {e}")
}

/// The colour of band `k` of `n` (green: low sensitivity, red: high).
fn band_color(k: usize, n: usize) -> RGBColor {
    let t = k as f64 / (n.max(2) - 1) as f64;
    let lerp = |a: (f64, f64, f64), b: (f64, f64, f64), s: f64| {
        RGBColor(
            (a.0 + (b.0 - a.0) * s) as u8,
            (a.1 + (b.1 - a.1) * s) as u8,
            (a.2 + (b.2 - a.2) * s) as u8,
        )
    };
    let (green, yellow, red) = (
        (120.0, 200.0, 130.0),
        (250.0, 230.0, 140.0),
        (225.0, 100.0, 90.0),
    );
    if t < 0.5 {
        lerp(green, yellow, 2.0 * t)
    } else {
        lerp(yellow, red, 2.0 * t - 1.0)
    }
}

/// The band of `v` among `levels` (0: below the first).
fn band(v: f64, levels: &[f64]) -> usize {
    levels.iter().take_while(|&&l| v >= l).count()
}

/// The area drawn: the transponders, the box and the start with a margin of
/// 30% of the baseline, widened to a square.
fn area(plan: &Plan) -> ((f64, f64), (f64, f64)) {
    let points = plan
        .layout
        .transponders()
        .iter()
        .map(Transponder::ne)
        .chain(plan.operating_box.corners)
        .chain([plan.start]);
    let (mut n0, mut n1, mut e0, mut e1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for p in points {
        n0 = n0.min(p[0]);
        n1 = n1.max(p[0]);
        e0 = e0.min(p[1]);
        e1 = e1.max(p[1]);
    }
    let margin = 0.3 * plan.operating_box.baseline_m;
    let half = 0.5 * (n1 - n0).max(e1 - e0) + margin;
    let (cn, ce) = (0.5 * (n0 + n1), 0.5 * (e0 + e1));
    ((cn - half, cn + half), (ce - half, ce + half))
}

/// Draws the map into `path` (PNG, whatever its name).
pub fn draw(plan: &Plan, path: &Path) -> anyhow::Result<()> {
    let (w, h) = (2 * PANEL, HEIGHT);
    let mut pixels = vec![0u8; 3 * w as usize * h as usize];
    render(plan, &mut pixels, (w, h))?;
    image::save_buffer_with_format(
        path,
        &pixels,
        w,
        h,
        image::ColorType::Rgb8,
        image::ImageFormat::Png,
    )
    .map_err(|e| anyhow::anyhow!("cannot write {}: {e}", path.display()))
}

/// Draws the map into `pixels` (RGB, `size` pixels).
fn render(plan: &Plan, pixels: &mut [u8], size: (u32, u32)) -> anyhow::Result<()> {
    font::register()?;
    let (north, east) = area(plan);
    let all: Vec<[f64; 2]> = plan
        .layout
        .transponders()
        .iter()
        .map(Transponder::ne)
        .collect();
    let (a, b) = (plan.pair[0].ne(), plan.pair[1].ne());
    let range = Grid::sample(north, east, SAMPLES, SAMPLES, |p| {
        range_sensitivity(&all, p)
    });
    let baseline = Grid::sample(north, east, SAMPLES, SAMPLES, |p| {
        baseline_sensitivity(a, b, p)
    });
    let root = BitMapBackend::with_buffer(pixels, size).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let (left, right) = root.split_horizontally(PANEL);
    panel(
        &left,
        plan,
        &range,
        &RANGE_LEVELS,
        &format!(
            "Fig. 2: position error per range error (m/m), {} transponders",
            all.len()
        ),
    )?;
    panel(
        &right,
        plan,
        &baseline,
        &BASELINE_LEVELS,
        &format!(
            "Fig. 3: position error per error of baseline T{}-T{} (m/m)",
            plan.pair[0].id, plan.pair[1].id
        ),
    )?;
    root.present().map_err(err)
}

fn panel(
    area: &DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>,
    plan: &Plan,
    grid: &Grid,
    levels: &[f64],
    title: &str,
) -> anyhow::Result<()> {
    let mut chart = ChartBuilder::on(area)
        .caption(title, (FAMILY, 17))
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(60)
        .build_cartesian_2d(grid.east_m.0..grid.east_m.1, grid.north_m.0..grid.north_m.1)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("east (m)")
        .y_desc("north (m)")
        .label_style((FAMILY, 12))
        .axis_desc_style((FAMILY, 13))
        .disable_mesh()
        .draw()
        .map_err(err)?;
    // Filled bands: one rectangle per sample, centred on it.
    let dn = (grid.north_m.1 - grid.north_m.0) / (grid.rows - 1) as f64;
    let de = (grid.east_m.1 - grid.east_m.0) / (grid.cols - 1) as f64;
    let undefined = RGBColor(90, 90, 90);
    let mut cells = Vec::with_capacity(grid.rows * grid.cols);
    for r in 0..grid.rows {
        for c in 0..grid.cols {
            let p = grid.at(r, c);
            let color = grid
                .get(r, c)
                .map_or(undefined, |v| band_color(band(v, levels), levels.len() + 1));
            cells.push(Rectangle::new(
                [
                    (p[1] - 0.5 * de, p[0] - 0.5 * dn),
                    (p[1] + 0.5 * de, p[0] + 0.5 * dn),
                ],
                color.filled(),
            ));
        }
    }
    chart.draw_series(cells).map_err(err)?;
    // The legend of the bands.
    for k in 0..=levels.len() {
        let label = match k {
            0 => format!("< {}", levels[0]),
            k if k == levels.len() => format!("≥ {}", levels[k - 1]),
            k => format!("{} to {}", levels[k - 1], levels[k]),
        };
        let c = band_color(k, levels.len() + 1);
        chart
            .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())
            .map_err(err)?
            .label(label)
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 14, y + 5)], c.filled()));
    }
    // Contour lines.
    let line = RGBColor(40, 40, 40);
    for &level in levels {
        let segments = grid.contour(level);
        chart
            .draw_series(segments.into_iter().map(|(p, q)| {
                PathElement::new(vec![(p[1], p[0]), (q[1], q[0])], line.stroke_width(1))
            }))
            .map_err(err)?;
    }
    // The baseline, the box, the start, the transponders.
    let [t1, t2] = plan.pair;
    let navy = RGBColor(20, 40, 140);
    chart
        .draw_series(std::iter::once(PathElement::new(
            vec![(t1.east_m, t1.north_m), (t2.east_m, t2.north_m)],
            navy.stroke_width(2),
        )))
        .map_err(err)?
        .label("baseline")
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 14, y)], navy.stroke_width(2)));
    let mut corners: Vec<(f64, f64)> = plan
        .operating_box
        .corners
        .iter()
        .map(|c| (c[1], c[0]))
        .collect();
    corners.push(corners[0]);
    let purple = RGBColor(120, 20, 140);
    chart
        .draw_series(std::iter::once(PathElement::new(
            corners,
            purple.stroke_width(3),
        )))
        .map_err(err)?
        .label("operating box (Fig. 4)")
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 14, y)], purple.stroke_width(3)));
    chart
        .draw_series(std::iter::once(Cross::new(
            (plan.start[1], plan.start[0]),
            6,
            BLACK.stroke_width(2),
        )))
        .map_err(err)?
        .label("start")
        .legend(|(x, y)| Cross::new((x + 7, y), 4, BLACK.stroke_width(2)));
    for t in plan.layout.transponders() {
        let at = (t.east_m, t.north_m);
        let label = format!("T{}", t.id);
        chart
            .draw_series(std::iter::once(
                EmptyElement::at(at)
                    + TriangleMarker::new((0, 0), 8, BLACK.filled())
                    + Text::new(label, (9, -16), (FAMILY, 15).into_font().color(&BLACK)),
            ))
            .map_err(err)?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font((FAMILY, 12))
        .draw()
        .map_err(err)?;
    Ok(())
}
