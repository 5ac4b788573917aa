//! Paper 003 §III's figures for a layout: the box of Fig. 4, the two
//! sensitivities against finite differences of the two-range fix, the
//! refusals, and the contours.

use std::path::Path;

use super::contour::Grid;
use super::layout::{Layout, LayoutError, Transponder};
use super::operating_box::{OperatingBox, OperatingBoxError};
use super::sensitivity::{baseline_frame, baseline_sensitivity, range_sensitivity};
use super::{Plan, PlanError, PlanOptions};

fn t(id: u32, north_m: f64, east_m: f64) -> Transponder {
    Transponder {
        id,
        north_m,
        east_m,
        depth_m: Some(20.0),
    }
}

/// The `lbl` scenario's two transponders (`nauta_sim`'s `LblLayout::Two`).
fn two() -> Layout {
    Layout::new(vec![t(1, -50.0, -150.0), t(2, 550.0, -150.0)]).expect("layout")
}

fn close(a: [f64; 2], b: [f64; 2]) -> bool {
    (a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9
}

#[test]
fn the_box_of_a_two_transponder_layout_is_a_quarter_to_one_baseline_away() {
    let plan = Plan::new(&two(), &PlanOptions::default()).expect("plan");
    let b = plan.operating_box;
    assert_eq!(b.baseline_m, 600.0);
    assert_eq!((b.near_m, b.far_m), (150.0, 600.0));
    assert_eq!(b.pair, [1, 2]);
    // The start (the origin) is east of the north-south baseline at
    // east = -150: the box spans east 0 to 450, north -50 to 550.
    let expected = [[-50.0, 0.0], [550.0, 0.0], [550.0, 450.0], [-50.0, 450.0]];
    for (c, e) in b.corners.iter().zip(expected) {
        assert!(close(*c, e), "{:?} against {expected:?}", b.corners);
    }
    let json = plan.to_json();
    assert_eq!(json["baseline_m"], 600.0);
    assert_eq!(json["box"][2][1], 450.0);
    // The scenario's mission box (500 m north x 400 m east from the origin)
    // lies inside it, as the layout's documentation says.
    for p in [[0.0, 0.0], [500.0, 0.0], [500.0, 400.0], [0.0, 400.0]] {
        assert!(b.contains(p), "{p:?}");
    }
    assert!(!b.contains([0.0, -10.0]) && !b.contains([600.0, 100.0]));
    // Inside the box: Fig. 2 at least √2 (two transponders), Fig. 3 from
    // 1/4 (far edge, middle) to 1 (near edge, middle).
    assert!(
        (plan.range_in_box.0 - 2f64.sqrt()).abs() < 0.01,
        "{:?}",
        plan.range_in_box
    );
    assert!(
        (plan.baseline_in_box.0 - 0.25).abs() < 0.01,
        "{:?}",
        plan.baseline_in_box
    );
    assert!(
        (plan.baseline_in_box.1 - 1.0).abs() < 0.01,
        "{:?}",
        plan.baseline_in_box
    );
}

#[test]
fn the_box_follows_the_start_side_and_any_baseline_direction() {
    let west = Plan::new(
        &two(),
        &PlanOptions {
            pair: None,
            start: [100.0, -400.0],
        },
    )
    .expect("plan");
    let expected = [
        [-50.0, -300.0],
        [550.0, -300.0],
        [550.0, -750.0],
        [-50.0, -750.0],
    ];
    for (c, e) in west.operating_box.corners.iter().zip(expected) {
        assert!(close(*c, e), "{:?}", west.operating_box.corners);
    }
    // A diagonal baseline of length 500 (3-4-5): the box's edges are 125
    // and 500 m from the baseline's line, its sides through the transponders.
    let (a, b) = (t(7, 0.0, 0.0), t(9, 300.0, 400.0));
    let bx = OperatingBox::new(&a, &b, [0.0, 500.0]).expect("box");
    assert!((bx.baseline_m - 500.0).abs() < 1e-12);
    for (c, near) in bx.corners.iter().zip([125.0, 125.0, 500.0, 500.0]) {
        let (_, y, _) = baseline_frame(a.ne(), b.ne(), *c).expect("frame");
        assert!((y.abs() - near).abs() < 1e-9, "{c:?}");
    }
    let (x0, ..) = baseline_frame(a.ne(), b.ne(), bx.corners[0]).expect("frame");
    let (x1, ..) = baseline_frame(a.ne(), b.ne(), bx.corners[1]).expect("frame");
    assert!((x0 + 250.0).abs() < 1e-9 && (x1 - 250.0).abs() < 1e-9);
    assert!(matches!(
        OperatingBox::new(&a, &b, [150.0, 200.0]),
        Err(OperatingBoxError::StartOnBaseline { .. })
    ));
}

/// The two-range fix in the frame of a baseline of length `l` centred on
/// the origin along x, on the +y side.
fn fix(r1: f64, r2: f64, l: f64) -> [f64; 2] {
    let x = (r1 * r1 - r2 * r2) / (2.0 * l);
    [x, (r1 * r1 - (x + l / 2.0).powi(2)).sqrt()]
}

#[test]
fn the_sensitivities_are_the_derivatives_of_the_two_range_fix() {
    let l = 600.0;
    // Transponders at x = ∓L/2 on the north axis: (north, east) = (x, y).
    let (t1, t2) = ([-l / 2.0, 0.0], [l / 2.0, 0.0]);
    for p in [
        [0.0f64, 150.0],
        [100.0, 400.0],
        [-450.0, 80.0],
        [700.0, 1500.0],
    ] {
        let r1 = (p[0] - t1[0]).hypot(p[1] - t1[1]);
        let r2 = (p[0] - t2[0]).hypot(p[1] - t2[1]);
        let at = fix(r1, r2, l);
        assert!(close(at, p), "{at:?} against {p:?}");
        let h = 1e-4;
        // Fig. 2: the Jacobian ∂p/∂(r1, r2), its Frobenius norm.
        let d1 = fix(r1 + h, r2, l);
        let d2 = fix(r1, r2 + h, l);
        let j = [
            (d1[0] - at[0]) / h,
            (d1[1] - at[1]) / h,
            (d2[0] - at[0]) / h,
            (d2[1] - at[1]) / h,
        ];
        let fd = j.iter().map(|v| v * v).sum::<f64>().sqrt();
        let ours = range_sensitivity(&[t1, t2], p).expect("defined");
        assert!((ours - fd).abs() < 1e-4 * fd, "{p:?}: {ours} against {fd}");
        // √2 / |sin α|.
        let (u, v) = ([p[0] - t1[0], p[1] - t1[1]], [p[0] - t2[0], p[1] - t2[1]]);
        let sin = (u[0] * v[1] - u[1] * v[0]).abs() / (r1 * r2);
        assert!((ours - 2f64.sqrt() / sin).abs() < 1e-9 * ours);
        // Fig. 3: the baseline lengthened about its midpoint.
        let dl = fix(r1, r2, l + h);
        let fd = ((dl[0] - at[0]) / h).hypot((dl[1] - at[1]) / h);
        let ours = baseline_sensitivity(t1, t2, p).expect("defined");
        assert!(
            (ours - fd).abs() < 1e-4 * fd.max(1e-3),
            "{p:?}: {ours} against {fd}"
        );
    }
    // Undefined on the baseline's line and at a transponder.
    assert_eq!(range_sensitivity(&[t1, t2], [100.0, 0.0]), None);
    assert_eq!(range_sensitivity(&[t1, t2], t1), None);
    assert_eq!(baseline_sensitivity(t1, t2, [1000.0, 0.0]), None);
    // Four transponders round a square: best (1, the least-squares floor of
    // four unit vectors at 90°) at the centre.
    let square = [[0.0, 0.0], [0.0, 100.0], [100.0, 0.0], [100.0, 100.0]];
    let centre = range_sensitivity(&square, [50.0, 50.0]).expect("defined");
    assert!((centre - 1.0).abs() < 1e-12, "{centre}");
}

#[test]
fn bad_layouts_are_refused_with_a_clear_error() {
    let coincident = Layout::new(vec![t(1, 10.0, 20.0), t(2, 10.0, 20.2)]).expect_err("coincident");
    assert!(matches!(
        coincident,
        LayoutError::Coincident { a: 1, b: 2, .. }
    ));
    assert!(
        coincident.to_string().contains("coincident"),
        "{coincident}"
    );
    assert!(matches!(
        Layout::new(vec![t(1, 0.0, 0.0)]),
        Err(LayoutError::TooFew { count: 1 })
    ));
    assert!(matches!(
        Layout::new(vec![t(3, 0.0, 0.0), t(3, 0.0, 500.0)]),
        Err(LayoutError::DuplicateId { id: 3 })
    ));
    for bad in [f64::NAN, f64::INFINITY, 2e5] {
        assert!(matches!(
            Layout::new(vec![t(1, 0.0, 0.0), t(2, bad, 0.0)]),
            Err(LayoutError::OutOfRange {
                id: 2,
                key: "north_m",
                ..
            })
        ));
    }
    let mut deep = t(2, 0.0, 500.0);
    deep.depth_m = Some(-3.0);
    assert!(matches!(
        Layout::new(vec![t(1, 0.0, 0.0), deep]),
        Err(LayoutError::OutOfRange { key: "depth_m", .. })
    ));
    // More than two transponders: the baseline is chosen, and must exist.
    let four = Layout::new(vec![
        t(1, -50.0, -150.0),
        t(2, 550.0, -150.0),
        t(3, -50.0, 550.0),
        t(4, 550.0, 550.0),
    ])
    .expect("four");
    assert!(matches!(
        Plan::new(&four, &PlanOptions::default()),
        Err(PlanError::NoPair { count: 4, .. })
    ));
    assert!(matches!(
        Plan::new(
            &four,
            &PlanOptions {
                pair: Some([1, 5]),
                start: [0.0, 0.0]
            }
        ),
        Err(PlanError::UnknownId { id: 5, .. })
    ));
    assert!(matches!(
        Plan::new(
            &four,
            &PlanOptions {
                pair: Some([2, 2]),
                start: [0.0, 0.0]
            }
        ),
        Err(PlanError::SamePair(2))
    ));
    let east = Plan::new(
        &four,
        &PlanOptions {
            pair: Some([3, 4]),
            start: [0.0, 0.0],
        },
    )
    .expect("east baseline");
    // The east baseline's box lies west of it, towards the start.
    assert!(close(east.operating_box.corners[0], [-50.0, 400.0]));
    assert!(close(east.operating_box.corners[3], [-50.0, -50.0]));
}

#[test]
fn the_csv_list_reads_and_its_errors_name_the_line() {
    let dir = std::env::temp_dir().join(format!("nauta-plan-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let write = |name: &str, text: &str| {
        let p = dir.join(name);
        std::fs::write(&p, text).expect("write");
        p
    };
    let good = write(
        "good.csv",
        "# the lbl scenario\n\nid,north_m,east_m,depth_m\n1,-50,-150,20\n 2 , 550 , -150 , 20 \n",
    );
    assert_eq!(Layout::from_csv_file(&good).expect("layout"), two());
    let flat = write("flat.csv", "id,north_m,east_m\n1,0,0\n2,0,300\n");
    assert_eq!(
        Layout::from_csv_file(&flat).expect("layout").transponders()[1].depth_m,
        None
    );
    let cases = [
        ("header.csv", "id,x,y\n1,0,0\n", ":1: header"),
        (
            "fields.csv",
            "id,north_m,east_m\n1,0,0\n2,0\n",
            ":3: 2 fields",
        ),
        (
            "number.csv",
            "id,north_m,east_m\n1,0,0\n2,abc,0\n",
            ":3: north_m \"abc\"",
        ),
        (
            "id.csv",
            "id,north_m,east_m\n-1,0,0\n2,0,0\n",
            ":2: id \"-1\"",
        ),
        ("empty.csv", "# nothing\n", ":1: no header"),
        (
            "same.csv",
            "id,north_m,east_m\n1,5,5\n2,5,5\n",
            "coincident",
        ),
    ];
    for (name, text, expected) in cases {
        let e = Layout::from_csv_file(&write(name, text))
            .expect_err(name)
            .to_string();
        assert!(e.contains(expected), "{name}: {e}");
        if expected.starts_with(':') {
            assert!(e.contains(name), "{name}: {e}");
        }
    }
    let missing = Layout::from_csv_file(Path::new("/nonexistent/layout.csv")).expect_err("missing");
    assert!(missing.to_string().contains("/nonexistent/layout.csv"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn contours_of_known_fields_lie_where_they_should() {
    // A plane: the level-3 contour of f = north is the line north = 3.
    let g = Grid::sample((0.0, 10.0), (0.0, 10.0), 11, 11, |p| Some(p[0]));
    let segs = g.contour(3.5);
    assert_eq!(segs.len(), 10);
    assert!(
        segs.iter()
            .all(|(a, b)| (a[0] - 3.5).abs() < 1e-12 && (b[0] - 3.5).abs() < 1e-12)
    );
    // A cone: the contour of the distance from the centre at 4 is a circle
    // (to the grid's resolution).
    let g = Grid::sample((-10.0, 10.0), (-10.0, 10.0), 81, 81, |p| {
        Some(p[0].hypot(p[1]))
    });
    let segs = g.contour(4.0);
    assert!(segs.len() > 40);
    for (a, b) in &segs {
        for p in [a, b] {
            assert!((p[0].hypot(p[1]) - 4.0).abs() < 0.05, "{p:?}");
        }
    }
    // Undefined samples are skipped, not crossed.
    let g = Grid::sample((0.0, 10.0), (0.0, 10.0), 11, 11, |p| {
        (p[1] > 5.0).then_some(p[0])
    });
    assert!(g.contour(3.5).iter().all(|(a, b)| a[1] > 5.0 && b[1] > 5.0));
}
