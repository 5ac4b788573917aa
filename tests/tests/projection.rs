//! The one local-origin projection (`nauta_estimation::local`) and the radii
//! of curvature against an independent implementation: pymap3d's
//! `geodetic2ned` and `rcurve` (PyPI, in the test venv), to 1 mm within 10 km
//! of the origin and 1e-9 relative.

use nauta_estimation::earth::{Geodetic, meridian_radius, transverse_radius};
use nauta_estimation::local::LocalTangentPlane;
use nauta_tests::run_python;
use serde_json::{Value, json};

#[test]
fn the_local_plane_and_the_radii_agree_with_pymap3d() {
    let origins = [(38.6, -9.3, 0.0), (-62.2, 179.9, 0.0), (0.0, 0.0, -20.0)];
    for (lat0, lon0, h0) in origins {
        let plane = LocalTangentPlane::new(f64::to_radians(lat0), f64::to_radians(lon0), h0)
            .expect("origin");
        // Points on rings up to 10 km, at depths to 200 m.
        let mut points = Vec::new();
        let mut ours = Vec::new();
        for (k, r) in [0.0, 1.0, 100.0, 2_500.0, 7_000.0, 10_000.0]
            .iter()
            .enumerate()
        {
            for j in 0..12 {
                let a = j as f64 * std::f64::consts::PI / 6.0;
                let ned = nauta_estimation::local::Ned {
                    north_m: r * a.cos(),
                    east_m: r * a.sin(),
                    down_m: (k * 40) as f64 - h0,
                };
                let g = plane.to_geodetic(&ned).expect("geodetic");
                points.push(json!([
                    g.lat_rad().to_degrees(),
                    g.lon_rad().to_degrees(),
                    g.height_m()
                ]));
                let back = plane.to_local(
                    &Geodetic::new(g.lat_rad(), g.lon_rad(), g.height_m()).expect("valid"),
                );
                ours.push([back.north_m, back.east_m, back.down_m]);
            }
        }
        let lats: Vec<f64> = (-18..=18).map(|k| k as f64 * 5.0).collect();
        let file = std::env::temp_dir().join(format!(
            "nauta-projection-{}-{lat0}.json",
            std::process::id()
        ));
        std::fs::write(
            &file,
            json!({"origin": [lat0, lon0, h0], "points": points, "lats": lats}).to_string(),
        )
        .expect("write job");
        let out: Value = serde_json::from_str(&run_python("projection.py", &[file.as_os_str()]))
            .expect("pymap3d's answer is JSON");
        let _ = std::fs::remove_file(&file);
        let theirs = out["ned"].as_array().expect("ned");
        assert_eq!(theirs.len(), ours.len());
        for (o, t) in ours.iter().zip(theirs) {
            for (axis, v) in o.iter().enumerate() {
                let w = t[axis].as_f64().expect("number");
                assert!(
                    (v - w).abs() <= 1e-3,
                    "origin ({lat0}, {lon0}): {o:?} against pymap3d {t}"
                );
            }
        }
        for (i, lat) in lats.iter().enumerate() {
            let l = lat.to_radians();
            for (name, ours, theirs) in [
                ("meridian", meridian_radius(l), &out["meridian"][i]),
                ("transverse", transverse_radius(l), &out["transverse"][i]),
            ] {
                let w = theirs.as_f64().expect("number");
                assert!(
                    ((ours - w) / w).abs() <= 1e-9,
                    "{name} radius at {lat}°: {ours} against pymap3d {w}"
                );
            }
        }
    }
}
