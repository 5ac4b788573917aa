//! The error-state model: the 18 error states, their continuous system
//! matrix `F` and noise, and the covariance propagation over a block of
//! IMU samples.
//!
//! **Error states** (truth minus estimate, except the attitude):
//!
//! | index | state | unit |
//! |-------|-------|------|
//! | 0-2   | `φ`, attitude error, NED: `C_b^n = (I + [φ×]) Ĉ_b^n` | rad |
//! | 3-5   | `δv^n`, velocity error, NED | m/s |
//! | 6-8   | `δp^n`, position error, NED metres | m |
//! | 9-11  | `δb_a`, accelerometer bias error, FRD | m/s² |
//! | 12-14 | `δb_g`, gyro bias error, FRD | rad/s |
//! | 15    | `b_ψ`, the heading source's slowly varying error | rad |
//! | 16-17 | `a_ψ`, `c_ψ`, its one-cycle deviation `a_ψ sin ψ + c_ψ cos ψ` | rad |
//!
//! The first 15 are the standard INS error state of Groves (2013) ch. 14
//! (INS/GNSS integration: the local-navigation-frame system model of
//! §14.2) and Farrell (2008) ch. 11 (the linearised NED error equations,
//! there with the position error in metres). Equation numbers are left
//! out: the signs below are derived here for our definitions, and the
//! books' numbering is not at hand to check. The 16th is a first-order
//! Gauss-Markov state (Groves ch. 3, the Kalman filter's system models)
//! for the heading measurement's correlated error: without it a
//! compass whose error wanders by a degree or two for minutes would be
//! taken as white noise, the yaw σ would shrink to a tenth of a degree and
//! the published position σ would not cover the cross-track error. The
//! 17th and 18th are the classical one-cycle compass deviation (the error
//! of a residual hard iron, a function of the heading, Groves §6.1 on
//! magnetic heading), Gauss-Markov with the bias's correlation time: an
//! attitude filter's course-dependent error is not a fixed function of the
//! heading, and as random constants the filter would learn them from the
//! turns once and for all): on parallel transects flown in alternate directions a
//! constant heading error cancels from leg to leg but a deviation does not,
//! and without these states the position σ would not grow with it.
//!
//! **System matrix** (our signs, from the definitions above; Groves's
//! attitude and bias errors are defined the other way round, so his
//! matrices differ in sign):
//!
//! ```text
//! φ̇   = −[ω_in^n ×] φ − Ĉ_b^n δb_g − Ĉ_b^n w_g
//! δv̇  = −[f^n ×] φ − 2[ω_ie^n ×] δv + (2γ/R) δp_D e_D − Ĉ_b^n δb_a − Ĉ_b^n w_a
//! δṗ  = δv                                   (NED metres, as Farrell)
//! δḃ_a = w_ba,   δḃ_g = w_bg                 (random walks)
//! ḃ_ψ = −b_ψ / τ_ψ + w_ψ,   E[w_ψ²] = 2σ_ψ²/τ_ψ   (Gauss-Markov)
//! ȧ_ψ = −a_ψ / τ_ψ + w_a,  ċ_ψ = −c_ψ / τ_ψ + w_c   (Gauss-Markov, σ_d)
//! ```
//!
//! Left out (below a centimetre over a survey with DVL aiding): the
//! transport-rate and Earth-rate terms in the position and velocity errors
//! (the latitude-error terms of the full model) and the attitude error's
//! coupling to the velocity error through `ω_en`.
//!
//! **Discretisation** (Groves ch. 3, the transition matrix as a truncated
//! power series of `F Δt` and the first-order system noise `Q_c Δt`; ch. 14
//! on propagating the covariance at a lower rate than the navigation): over a block of `N` IMU samples of total
//! length `T`, `F̄` is `F` at the block's mean `f^n` and mean `Ĉ_b^n`
//! (`Σ F_k Δt_k = F̄ T` exactly, since `F` is linear in both), and
//! `Φ = I + F̄T + ½(F̄T)²`, `Q_d = Q_c T`. With `N = 10` at 100 Hz the block is 0.1 s, far below the
//! 84-minute Schuler period and every other time constant of the error
//! model.

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use super::params::EkfConfig;

/// Number of error states.
pub const N: usize = 18;
/// Attitude error `φ`.
pub const ATT: usize = 0;
/// Velocity error `δv`.
pub const VEL: usize = 3;
/// Position error `δp` (NED metres).
pub const POS: usize = 6;
/// Accelerometer bias error.
pub const BA: usize = 9;
/// Gyro bias error.
pub const BG: usize = 12;
/// Heading measurement bias.
pub const BH: usize = 15;
/// Heading deviation, sine coefficient.
pub const DA: usize = 16;
/// Heading deviation, cosine coefficient.
pub const DC: usize = 17;

/// The error covariance.
pub type Cov = SMatrix<f64, N, N>;
/// An error state.
pub type ErrorState = SVector<f64, N>;

/// `[a ×]`, the cross-product matrix.
pub fn skew(a: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -a.z, a.y, a.z, 0.0, -a.x, -a.y, a.x, 0.0)
}

/// What a block of IMU samples accumulates for the covariance step.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Block {
    /// `Σ f^n Δt`, m/s.
    pub f_dt: [f64; 3],
    /// `Σ Ĉ_b^n Δt`, row-major, s.
    pub c_dt: [f64; 9],
    /// `Σ ω_in^n Δt`, rad.
    pub w_dt: [f64; 3],
    /// `Σ Δt`, s.
    pub t_s: f64,
    /// Samples in the block.
    pub samples: u32,
}

impl Block {
    /// Adds one sample's `f^n`, `Ĉ_b^n`, `ω_in^n` over `dt`.
    pub fn push(&mut self, f_n: &Vector3<f64>, c: &Matrix3<f64>, w_in: &Vector3<f64>, dt: f64) {
        for i in 0..3 {
            self.f_dt[i] += f_n[i] * dt;
            self.w_dt[i] += w_in[i] * dt;
            for j in 0..3 {
                self.c_dt[3 * i + j] += c[(i, j)] * dt;
            }
        }
        self.t_s += dt;
        self.samples += 1;
    }
}

/// The heading bias state's Gauss-Markov model: stationary σ, rad, and
/// correlation time, s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeadingBias {
    /// Stationary σ, rad.
    pub std_rad: f64,
    /// Correlation time, s (of the deviation coefficients too).
    pub time_s: f64,
    /// Stationary σ of each deviation coefficient, rad.
    pub deviation_std_rad: f64,
}

/// The continuous-time noise spectral densities, diagonal of `Q_c`.
fn q_c(cfg: &EkfConfig, bh: HeadingBias) -> SVector<f64, N> {
    let mut q = SVector::<f64, N>::zeros();
    for i in 0..3 {
        q[ATT + i] = cfg.gyro_noise * cfg.gyro_noise;
        q[VEL + i] = cfg.accel_noise * cfg.accel_noise;
        q[BA + i] = cfg.accel_bias_walk * cfg.accel_bias_walk;
        q[BG + i] = cfg.gyro_bias_walk * cfg.gyro_bias_walk;
    }
    q[BH] = 2.0 * bh.std_rad * bh.std_rad / bh.time_s;
    q[DA] = 2.0 * bh.deviation_std_rad * bh.deviation_std_rad / bh.time_s;
    q[DC] = q[DA];
    q
}

/// `F̄ T` of a block (module docs), with `γ/R` and `ω_ie^n` at the block's
/// end.
fn f_t(b: &Block, gamma_over_r: f64, w_ie: &Vector3<f64>, tau_h: f64) -> Cov {
    let mut f = Cov::zeros();
    let f_dt = Vector3::from(b.f_dt);
    let w_dt = Vector3::from(b.w_dt);
    let c_dt = Matrix3::from_row_slice(&b.c_dt);
    let t = b.t_s;
    f.fixed_view_mut::<3, 3>(ATT, ATT)
        .copy_from(&(-skew(&w_dt)));
    f.fixed_view_mut::<3, 3>(ATT, BG).copy_from(&(-c_dt));
    f.fixed_view_mut::<3, 3>(VEL, ATT)
        .copy_from(&(-skew(&f_dt)));
    f.fixed_view_mut::<3, 3>(VEL, VEL)
        .copy_from(&(-2.0 * t * skew(w_ie)));
    f[(VEL + 2, POS + 2)] = 2.0 * gamma_over_r * t;
    f.fixed_view_mut::<3, 3>(VEL, BA).copy_from(&(-c_dt));
    for i in 0..3 {
        f[(POS + i, VEL + i)] = t;
    }
    f[(BH, BH)] = -t / tau_h;
    f[(DA, DA)] = -t / tau_h;
    f[(DC, DC)] = -t / tau_h;
    f
}

/// Propagates `p` over the block `b` (module docs) and empties the block;
/// `bh` is the heading bias state's model (it depends on the heading
/// source).
pub fn propagate_covariance(
    p: &mut Cov,
    b: &mut Block,
    cfg: &EkfConfig,
    bh: HeadingBias,
    gamma_over_r: f64,
    w_ie: &Vector3<f64>,
) {
    if b.samples == 0 || !(b.t_s > 0.0) {
        *b = Block::default();
        return;
    }
    let ft = f_t(b, gamma_over_r, w_ie, bh.time_s);
    let phi = Cov::identity() + ft + 0.5 * ft * ft;
    let mut next = phi * *p * phi.transpose();
    let q = q_c(cfg, bh);
    for i in 0..N {
        next[(i, i)] += q[i] * b.t_s;
    }
    *p = 0.5 * (next + next.transpose());
    *b = Block::default();
}
