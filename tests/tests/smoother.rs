//! Golden test of paper 004's smoother (`nauta_estimation::smoother`)
//! against an independent implementation: pykalman's Kalman filter and RTS
//! smoother (PyPI, in the test venv, `tests/py/rts_smoother.py`) on a
//! linear version of the LBL problem (`nauta_tests::smoother_fixture`),
//! with dense and scarce range corrections, time-varying `b_i` and `Q_i`.

use nalgebra::{SMatrix, Vector1};
use nauta_estimation::smoother::{LinearForward, smooth};
use nauta_tests::run_python;
use nauta_tests::smoother_fixture::Fixture;
use serde_json::Value;

fn vector(v: &Value) -> Vec<f64> {
    v.as_array()
        .expect("array")
        .iter()
        .map(|x| x.as_f64().expect("number"))
        .collect()
}

fn matrix(v: &Value) -> SMatrix<f64, 4, 4> {
    let rows: Vec<Vec<f64>> = v.as_array().expect("rows").iter().map(vector).collect();
    SMatrix::from_fn(|r, c| rows[r][c])
}

#[test]
fn the_smoother_agrees_with_pykalman_on_a_linear_lbl_problem() {
    // 10 minutes at 10 Hz: legs, turns and a 60 s blackout.
    let fixture = Fixture::generate(11, 6_000);
    let mut forward = LinearForward::with_capacity(0, fixture.x0, fixture.p0, fixture.steps.len());
    for (i, step) in fixture.steps.iter().enumerate() {
        if i > 0 {
            forward.predict(i as u64 * 100_000_000, &step.model);
        }
        if let Some((h, z, r)) = &step.measurement {
            forward
                .update(&Vector1::new(*z), h, &SMatrix::<f64, 1, 1>::new(*r))
                .expect("update");
        }
    }
    let pass = forward.into_steps();
    let ours = smooth(&pass).expect("smooth");

    let file = std::env::temp_dir().join(format!("nauta-smoother-{}.json", std::process::id()));
    std::fs::write(&file, fixture.to_json().to_string()).expect("write fixture");
    let out = run_python("rts_smoother.py", &[file.as_os_str()]);
    let _ = std::fs::remove_file(&file);
    let theirs: Value = serde_json::from_str(&out).expect("pykalman's answer is JSON");

    let close = |what: &str, i: usize, a: f64, b: f64, scale: f64| {
        assert!(
            (a - b).abs() <= 1e-8 * scale,
            "step {i}: {what} {a} against pykalman's {b}"
        );
    };
    let n = pass.len();
    for key in [
        "filtered_means",
        "filtered_covariances",
        "smoothed_means",
        "smoothed_covariances",
    ] {
        assert_eq!(theirs[key].as_array().map(Vec::len), Some(n), "{key}");
    }
    for i in 0..n {
        let fm = vector(&theirs["filtered_means"][i]);
        let fp = matrix(&theirs["filtered_covariances"][i]);
        let sm = vector(&theirs["smoothed_means"][i]);
        let sp = matrix(&theirs["smoothed_covariances"][i]);
        let scale_p = pass[i].p_post.amax();
        for r in 0..4 {
            close("filtered state", i, pass[i].x_post[r], fm[r], 1e3);
            close("smoothed state", i, ours[i].x[r], sm[r], 1e3);
            for c in 0..4 {
                close("filtered P", i, pass[i].p_post[(r, c)], fp[(r, c)], scale_p);
                close("smoothed P", i, ours[i].p[(r, c)], sp[(r, c)], scale_p);
            }
        }
    }
    // The fixture is not trivial: the smoother changed the estimate and
    // shrank the covariance, most in the blackout.
    let mid_blackout = 3_300;
    let filtered = pass[mid_blackout].p_post;
    let smoothed = ours[mid_blackout].p;
    assert!(
        smoothed[(0, 0)] + smoothed[(1, 1)] < 0.5 * (filtered[(0, 0)] + filtered[(1, 1)]),
        "blackout: trace P_xy {} smoothed against {} filtered",
        smoothed[(0, 0)] + smoothed[(1, 1)],
        filtered[(0, 0)] + filtered[(1, 1)]
    );
}
