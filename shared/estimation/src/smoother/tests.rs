//! The smoother against the batch solution, its covariance property, its
//! refusals, and the discretisation against closed forms.

use std::ops::AddAssign;

use nalgebra::{DMatrix, DVector, Matrix2, SMatrix, SVector, Vector1, Vector2};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::*;

const DT_NS: u64 = 100_000_000;

/// A constant-velocity track (position, velocity) at 10 Hz with a known
/// acceleration input and a position fix every 7th step.
fn constant_velocity(steps: usize) -> (LinearForward<2>, Vec<Discretised<2>>, Vec<Option<f64>>) {
    let a = Matrix2::new(0.0, 1.0, 0.0, 0.0);
    let qc = Matrix2::new(0.0, 0.0, 0.0, 0.04);
    let mut f = LinearForward::new(0, Vector2::new(0.0, 1.0), Matrix2::new(4.0, 0.0, 0.0, 1.0));
    let mut models = Vec::new();
    let mut fixes = vec![None];
    for i in 1..=steps {
        let accel = 0.3 * (i as f64 * 0.2).sin();
        let d = Discretised::of(&a, &qc, &Vector2::new(0.0, accel), 0.1).expect("discretise");
        f.predict(i as u64 * DT_NS, &d);
        models.push(d);
        fixes.push(None);
        if i % 7 == 0 {
            let z = 0.1 * i as f64 + 0.4 * (i as f64).cos();
            fixes[i] = Some(z);
            f.update(
                &Vector1::new(z),
                &SMatrix::<f64, 1, 2>::new(1.0, 0.0),
                &SMatrix::<f64, 1, 1>::new(0.25),
            )
            .expect("update");
        }
    }
    (f, models, fixes)
}

/// The joint Gaussian of every state given every fix, in information form:
/// prior on x₀, `x_{i+1} = φ x_i + b + w`, `z = H x + v`.
fn batch(
    x0: Vector2<f64>,
    p0: Matrix2<f64>,
    models: &[Discretised<2>],
    fixes: &[Option<f64>],
) -> (DVector<f64>, DMatrix<f64>) {
    let n = fixes.len();
    let mut lambda = DMatrix::<f64>::zeros(2 * n, 2 * n);
    let mut eta = DVector::<f64>::zeros(2 * n);
    let p0i = p0.try_inverse().expect("P0");
    lambda.view_mut((0, 0), (2, 2)).add_assign(&p0i);
    eta.rows_mut(0, 2).add_assign(&(p0i * x0));
    for (i, d) in models.iter().enumerate() {
        let qi = d.q.try_inverse().expect("Q invertible");
        // Residual x_{i+1} − φ x_i − b with J = [−φ, I].
        let mut j = DMatrix::<f64>::zeros(2, 2 * n);
        j.view_mut((0, 2 * i), (2, 2)).copy_from(&(-d.phi));
        j.view_mut((0, 2 * i + 2), (2, 2))
            .copy_from(&Matrix2::identity());
        let qi = DMatrix::from_column_slice(2, 2, qi.as_slice());
        lambda += j.transpose() * &qi * &j;
        eta += j.transpose() * &qi * DVector::from_column_slice(d.b.as_slice());
    }
    for (i, z) in fixes.iter().enumerate() {
        if let Some(z) = z {
            lambda[(2 * i, 2 * i)] += 1.0 / 0.25;
            eta[2 * i] += z / 0.25;
        }
    }
    let cov = lambda.try_inverse().expect("information invertible");
    (&cov * eta, cov)
}

#[test]
fn rts_equals_the_batch_solution_of_a_linear_system() {
    let (f, models, fixes) = constant_velocity(60);
    let first = f.steps()[0];
    let smoothed = smooth(f.steps()).expect("smooth");
    let (mean, cov) = batch(first.x_post, first.p_post, &models, &fixes);
    assert_eq!(smoothed.len(), fixes.len());
    for (i, s) in smoothed.iter().enumerate() {
        assert_eq!(s.stamp_ns, i as u64 * DT_NS);
        for r in 0..2 {
            let scale = mean[2 * i + r].abs().max(1.0);
            assert!(
                (s.x[r] - mean[2 * i + r]).abs() <= 1e-9 * scale,
                "step {i}: x {} against the batch {}",
                s.x,
                mean.rows(2 * i, 2)
            );
            for c in 0..2 {
                let b = cov[(2 * i + r, 2 * i + c)];
                assert!(
                    (s.p[(r, c)] - b).abs() <= 1e-9 * b.abs().max(1e-3),
                    "step {i}: P {} against the batch {}",
                    s.p,
                    cov.view((2 * i, 2 * i), (2, 2))
                );
            }
        }
    }
    // The last step is the filter's own.
    let last = f.current();
    assert_eq!(smoothed[60].x, last.x_post);
    assert_eq!(smoothed[60].p, last.p_post);
}

/// A random linear system of dimension 3 with scarce scalar measurements.
fn random_pass(seed: u64, steps: usize) -> Vec<ForwardStep<3>> {
    random_pass_with(seed, steps, |_, _| {})
}

/// [`random_pass`], `edit(i, filter)` called after each step's corrections.
fn random_pass_with(
    seed: u64,
    steps: usize,
    mut edit: impl FnMut(usize, &mut LinearForward<3>),
) -> Vec<ForwardStep<3>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut u = |s: f64| rng.random_range(-s..s);
    let x0 = SVector::<f64, 3>::new(u(10.0), u(10.0), u(1.0));
    let l = SMatrix::<f64, 3, 3>::from_fn(|_, _| u(1.0));
    let p0 = l * l.transpose() + SMatrix::identity() * 0.1;
    let mut f = LinearForward::new(0, x0, p0);
    for i in 1..=steps {
        let phi = SMatrix::<f64, 3, 3>::identity() + SMatrix::from_fn(|_, _| u(0.2));
        let lq = SMatrix::<f64, 3, 3>::from_fn(|_, _| u(0.1));
        let q = lq * lq.transpose() + SMatrix::identity() * 1e-4;
        let b = SVector::<f64, 3>::from_fn(|_, _| u(1.0));
        f.predict(i as u64 * DT_NS, &Discretised { phi, q, b });
        if u(1.0) > 0.4 {
            let h = SMatrix::<f64, 1, 3>::from_fn(|_, _| u(1.0));
            let r = SMatrix::<f64, 1, 1>::new(0.01 + u(1.0).abs());
            f.update(&Vector1::new(u(20.0)), &h, &r).expect("update");
        }
        edit(i, &mut f);
    }
    f.into_steps()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// `P_{i|N} ≤ P_i`: the difference is positive semi-definite at every
    /// step (the smoother never knows less than the filter).
    #[test]
    fn smoothed_covariance_never_exceeds_the_filtered(seed in any::<u64>(), steps in 1usize..80) {
        let pass = random_pass(seed, steps);
        let smoothed = smooth(&pass).expect("smooth");
        for (i, (f, s)) in pass.iter().zip(&smoothed).enumerate() {
            let d = f.p_post - s.p;
            let min = d.symmetric_eigen().eigenvalues.min();
            prop_assert!(
                min >= -1e-9 * f.p_post.amax().max(1.0),
                "step {}: P_post − P_smoothed has eigenvalue {} ({} − {})", i, min, f.p_post, s.p
            );
            prop_assert!(s.p.cholesky().is_some());
        }
    }

    /// No input panics: values of every kind (NaN, ±∞, huge, tiny, zero)
    /// anywhere, stamps in any order, give a result or an error, and a
    /// result is finite.
    #[test]
    fn no_input_panics(
        values in proptest::collection::vec(
            prop_oneof![
                Just(f64::NAN), Just(f64::INFINITY), Just(f64::NEG_INFINITY),
                Just(0.0), Just(1e308), Just(-1e308), Just(1e-308),
                -10.0f64..10.0, Just(1.0),
            ],
            0..(6 * 15),
        ),
        stamps in proptest::collection::vec(any::<u64>(), 6),
    ) {
        let steps: Vec<ForwardStep<2>> = values
            .chunks_exact(15)
            .zip(&stamps)
            .map(|(v, &stamp_ns)| {
                let m = |o: usize| Matrix2::new(v[o], v[o + 1], v[o + 2], v[o + 3]);
                ForwardStep {
                    stamp_ns,
                    phi: m(0),
                    x_prior: Vector2::new(v[4], v[5]),
                    p_prior: m(6),
                    x_post: Vector2::new(v[10], v[11]),
                    p_post: Matrix2::new(v[12], v[13], v[13], v[14]),
                }
            })
            .collect();
        if let Ok(out) = smooth(&steps) {
            prop_assert_eq!(out.len(), steps.len());
            for s in out {
                prop_assert!(s.x.iter().chain(s.p.iter()).all(|v| v.is_finite()));
            }
        }
    }
}

#[test]
fn an_empty_pass_smooths_to_nothing_and_one_step_to_itself() {
    assert!(smooth::<4>(&[]).expect("empty").is_empty());
    let pass = random_pass(3, 0);
    let out = smooth(&pass).expect("one step");
    assert_eq!(out.len(), 1);
    assert_eq!(out[0].x, pass[0].x_post);
    assert_eq!(out[0].p, pass[0].p_post);
}

#[test]
fn a_non_finite_value_is_refused_naming_its_step_and_field() {
    let clean = random_pass(5, 20);
    type Spoil = fn(&mut ForwardStep<3>);
    let cases: [(StepField, Spoil); 5] = [
        (StepField::Phi, |s| s.phi[(1, 2)] = f64::NAN),
        (StepField::XPrior, |s| s.x_prior[0] = f64::INFINITY),
        (StepField::PPrior, |s| s.p_prior[(0, 0)] = f64::NAN),
        (StepField::XPost, |s| s.x_post[2] = f64::NEG_INFINITY),
        (StepField::PPost, |s| s.p_post[(2, 1)] = f64::NAN),
    ];
    for (field, spoil) in cases {
        let mut pass = clean.clone();
        spoil(&mut pass[11]);
        let err = smooth(&pass).expect_err("refused");
        assert_eq!(
            err,
            SmoothError::NonFinite {
                step: 11,
                stamp_ns: 11 * DT_NS,
                field
            }
        );
        let mut out = vec![];
        assert!(smooth_into(&pass, &mut out).is_err());
        assert!(out.is_empty(), "no partial result");
    }
}

#[test]
fn a_covariance_that_is_not_positive_definite_is_refused() {
    let clean = random_pass(6, 20);
    let mut pass = clean.clone();
    pass[7].p_prior = -pass[7].p_prior;
    assert_eq!(
        smooth(&pass),
        Err(SmoothError::NotPositiveDefinite {
            step: 7,
            stamp_ns: 7 * DT_NS,
            field: StepField::PPrior
        })
    );
    let mut pass = clean.clone();
    pass[20].p_post = SMatrix::zeros();
    assert!(matches!(
        smooth(&pass),
        Err(SmoothError::NotPositiveDefinite {
            step: 20,
            field: StepField::PPost,
            ..
        })
    ));
    let mut pass = clean;
    pass[3].p_post[(1, 1)] = -1.0;
    assert!(matches!(
        smooth(&pass),
        Err(SmoothError::NotPositiveDefinite {
            step: 3,
            field: StepField::PPost,
            ..
        })
    ));
}

#[test]
fn a_stamp_going_backwards_is_refused() {
    let mut pass = random_pass(7, 10);
    pass[4].stamp_ns = 2 * DT_NS;
    assert_eq!(
        smooth(&pass),
        Err(SmoothError::StampBackwards {
            step: 4,
            stamp_ns: 2 * DT_NS,
            previous_ns: 3 * DT_NS
        })
    );
    // Equal stamps are two steps at one instant (a zero-length step).
    let mut pass = random_pass(7, 10);
    pass[4].stamp_ns = 3 * DT_NS;
    assert!(smooth(&pass).is_ok());
}

#[test]
fn the_lbl_model_discretises_exactly() {
    // Paper 004 eq. 3: ∂F/∂E = [[0, 0, 1, 0], [0, 0, 0, 1], 0, 0], A² = 0.
    let mut a = SMatrix::<f64, 4, 4>::zeros();
    a[(0, 2)] = 1.0;
    a[(1, 3)] = 1.0;
    let qc = SMatrix::<f64, 4, 4>::from_diagonal(&SVector::<f64, 4>::new(0.3, 0.2, 1e-4, 2e-4));
    let e = SVector::<f64, 4>::new(100.0, -50.0, 0.2, -0.1);
    let (u, v) = (1.1, -0.4);
    let f = SVector::<f64, 4>::new(u + e[2], v + e[3], 0.0, 0.0);
    let h = 0.1;
    let d = Discretised::of(&a, &qc, &(f - a * e), h).expect("discretise");
    let phi = SMatrix::<f64, 4, 4>::identity() + a * h;
    let q = qc * h
        + (a * qc + qc * a.transpose()) * (h * h / 2.0)
        + a * qc * a.transpose() * (h * h * h / 3.0);
    assert!((d.phi - phi).amax() < 1e-15);
    assert!((d.q - q).amax() < 1e-15, "{} against {}", d.q, q);
    // φ E + b is the exact propagation of the affine dynamics.
    let next = d.phi * e + d.b;
    let exact = SVector::<f64, 4>::new(e[0] + (u + e[2]) * h, e[1] + (v + e[3]) * h, e[2], e[3]);
    assert!((next - exact).amax() < 1e-12);
}

#[test]
fn a_stiff_and_a_rotating_model_discretise_to_their_closed_forms() {
    // Scalar decay ẋ = −k x + c: ‖A‖ h = 30 needs halvings.
    let (k, c, q, h) = (3.0, 2.0, 0.5, 10.0);
    let d = Discretised::<1>::of(
        &SMatrix::<f64, 1, 1>::new(-k),
        &SMatrix::<f64, 1, 1>::new(q),
        &SVector::<f64, 1>::new(c),
        h,
    )
    .expect("discretise");
    let e = (-k * h).exp();
    assert!((d.phi[0] - e).abs() < 1e-15);
    assert!((d.b[0] - c * (1.0 - e) / k).abs() < 1e-12);
    assert!((d.q[0] - q * (1.0 - e * e) / (2.0 * k)).abs() < 1e-12);
    // A rotation at ω: φ = R(ωh), an isotropic Q stays isotropic: q h I.
    let w = 0.7;
    let d = Discretised::<2>::of(
        &Matrix2::new(0.0, -w, w, 0.0),
        &(Matrix2::identity() * q),
        &Vector2::zeros(),
        h,
    )
    .expect("discretise");
    let (s, co) = (w * h).sin_cos();
    assert!(
        (d.phi - Matrix2::new(co, -s, s, co)).amax() < 1e-12,
        "{}",
        d.phi
    );
    assert!(
        (d.q - Matrix2::identity() * q * h).amax() < 1e-11,
        "{}",
        d.q
    );
}

#[test]
fn bad_dynamics_are_refused() {
    let a = Matrix2::identity();
    let q = Matrix2::identity();
    let c = Vector2::zeros();
    assert_eq!(
        Discretised::of(&a, &q, &c, -0.1),
        Err(DiscretiseError::NegativeInterval)
    );
    assert_eq!(
        Discretised::of(&a, &q, &c, f64::NAN),
        Err(DiscretiseError::NonFinite)
    );
    assert_eq!(
        Discretised::of(&(a * f64::INFINITY), &q, &c, 0.1),
        Err(DiscretiseError::NonFinite)
    );
    assert_eq!(
        Discretised::of(&(a * 1e300), &q, &c, 1e10),
        Err(DiscretiseError::Overflow)
    );
    let zero = Discretised::of(&a, &q, &c, 0.0).expect("zero step");
    assert_eq!(zero.phi, Matrix2::identity());
    assert_eq!(zero.q, Matrix2::zeros());
}

/// [`random_pass`] of 60 steps whose step `k` resets its state (a GPS fix
/// at the surface): a posterior that knows less than its prior.
fn reset_pass(k: usize) -> Vec<ForwardStep<3>> {
    random_pass_with(9, 60, |i, f| {
        if i == k {
            f.reset(
                f.current().x_prior + SVector::<f64, 3>::new(25.0, -10.0, 0.0),
                f.current().p_prior + SMatrix::identity() * 50.0,
            );
        }
    })
}

#[test]
fn a_reset_restarts_the_backward_pass() {
    let k = 40;
    let pass = reset_pass(k);
    assert!(is_restart(&pass[k]));
    assert!(
        !pass.iter().take(k).skip(1).any(is_restart),
        "corrections are no restarts"
    );
    let out = smooth(&pass).expect("smooth");
    // The step before keeps its filtered estimate, and the stretch before it
    // is smoothed as if the mission ended there.
    assert_eq!(out[k - 1].x, pass[k - 1].x_post);
    assert_eq!(out[k - 1].p, pass[k - 1].p_post);
    let alone = smooth(&pass[..k]).expect("smooth the first stretch");
    assert_eq!(&out[..k], &alone[..]);
    for (f, s) in pass.iter().zip(&out) {
        let min = (f.p_post - s.p).symmetric_eigen().eigenvalues.min();
        assert!(min >= -1e-9 * f.p_post.amax(), "{min}");
    }
}

#[test]
fn a_bridged_reset_carries_the_fix_back() {
    let k = 40;
    let pass = reset_pass(k);
    let cut = smooth(&pass).expect("smooth");
    assert_eq!(smooth_bridged(&pass, 0).expect("m = 0"), cut);
    let bridged = smooth_bridged(&pass, 2).expect("bridged");
    // After the reset nothing changes; before it the track moves towards
    // the smoothed position at the reset: the step before, predicted to
    // it, lands closer.
    assert_eq!(&bridged[k..], &cut[k..]);
    let miss = |s: &[SmoothedStep<3>]| {
        let d = pass[k].phi * s[k - 1].x - s[k].x;
        d[0].hypot(d[1])
    };
    assert!(
        miss(&bridged) < miss(&cut),
        "{} {}",
        miss(&bridged),
        miss(&cut)
    );
    // And P_smoothed ≤ P_filtered still holds everywhere.
    for (f, s) in pass.iter().zip(&bridged) {
        let min = (f.p_post - s.p).symmetric_eigen().eigenvalues.min();
        assert!(min >= -1e-9 * f.p_post.amax(), "{min}");
    }
}
