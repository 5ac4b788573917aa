//! The aiding measurements' models: residual `ν = z − ẑ`, Jacobian `H`
//! with respect to the error state ([`super::model`]) and noise `R`
//! (Groves 2013 ch. 16, multisensor integration, for the DVL, depth and
//! compass, ch. 14 for position; the Jacobians below are derived here for
//! our error-state signs).

use nalgebra::{Matrix1, Matrix2, Matrix3, SMatrix, Vector1, Vector2, Vector3};

use super::filter::Filter;
use super::model::{ATT, BG, BH, DA, DC, N, POS, VEL, skew};
use super::params::EkfConfig;
use crate::attitude::wrap_pi;

/// One measurement of dimension `M`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Measurement<const M: usize> {
    /// `z − ẑ`.
    pub nu: SMatrix<f64, M, 1>,
    /// `∂ẑ/∂δx`.
    pub h: SMatrix<f64, M, N>,
    /// Noise covariance.
    pub r: SMatrix<f64, M, M>,
}

/// DVL bottom-track velocity in the DVL frame (the Doppler velocity with
/// lever arm: `ṽ_d = M_bᵀ (C_b^nᵀ v^n + ω_nb^b × l)`,
/// `M_b` the DVL → body rotation, `l` the lever arm). With
/// `C = (I + [φ×]) Ĉ`: `C_b^nᵀ v = Ĉᵀ v̂ + Ĉᵀ δv + Ĉᵀ [v̂ ×] φ`, and with
/// `ω = ω̂ − δb_g`: `ω × l = ω̂ × l + [l ×] δb_g`.
pub fn dvl(f: &Filter, cfg: &EkfConfig, z: &Vector3<f64>) -> Measurement<3> {
    let c = f.c_nb();
    let mt = cfg.dvl_to_body.transpose();
    let v = f.nav.v_ned_m_s.to_nalgebra();
    let ct = c.transpose();
    let pred = mt * (ct * v + f.omega_b.cross(&cfg.dvl_lever_arm));
    let mut h = SMatrix::<f64, 3, N>::zeros();
    h.fixed_view_mut::<3, 3>(0, ATT)
        .copy_from(&(mt * ct * skew(&v)));
    h.fixed_view_mut::<3, 3>(0, VEL).copy_from(&(mt * ct));
    h.fixed_view_mut::<3, 3>(0, BG)
        .copy_from(&(mt * skew(&cfg.dvl_lever_arm)));
    Measurement {
        nu: z - pred,
        h,
        r: Matrix3::identity() * (cfg.dvl_std * cfg.dvl_std),
    }
}

/// The NED velocity a DVL sample gives when it re-anchors the velocity
/// (the inverse of [`dvl`] at the estimated attitude).
pub fn dvl_velocity_ned(f: &Filter, cfg: &EkfConfig, z: &Vector3<f64>) -> Vector3<f64> {
    f.c_nb() * (cfg.dvl_to_body * z - f.omega_b.cross(&cfg.dvl_lever_arm))
}

/// Depth (tared gauge): `ẑ = −h`, so `H = e_D` on `δp` (NED, down).
pub fn depth(f: &Filter, cfg: &EkfConfig, z: f64) -> Measurement<1> {
    let mut h = SMatrix::<f64, 1, N>::zeros();
    h[(0, POS + 2)] = 1.0;
    Measurement {
        nu: Vector1::new(z - f.nav.depth_m()),
        h,
        r: Matrix1::new(cfg.depth_std * cfg.depth_std),
    }
}

/// Horizontal position (GPS or a fix) of covariance `r`, NED metres: the
/// residual is the offset of the measured latitude and longitude from the
/// estimate, `(ΔL (R_N + h), Δλ (R_E + h) cos L)` (the curvilinear-to-local
/// scaling, Groves ch. 2); `H = [I₂]` on `δp_N, δp_E`.
pub fn horizontal(f: &Filter, lat: f64, lon: f64, r: Matrix2<f64>) -> Measurement<2> {
    let (m_lat, m_lon) = f.metres_per_rad();
    let mut h = SMatrix::<f64, 2, N>::zeros();
    h[(0, POS)] = 1.0;
    h[(1, POS + 1)] = 1.0;
    Measurement {
        nu: Vector2::new(
            (lat - f.nav.lat_rad) * m_lat,
            wrap_pi(lon - f.nav.lon_rad) * m_lon,
        ),
        h,
        r,
    }
}

/// GPS velocity, NED: `H = [I₃]` on `δv`.
pub fn velocity(f: &Filter, z: &Vector3<f64>, std: f64) -> Measurement<3> {
    let mut h = SMatrix::<f64, 3, N>::zeros();
    h.fixed_view_mut::<3, 3>(0, VEL)
        .copy_from(&Matrix3::identity());
    Measurement {
        nu: z - f.nav.v_ned_m_s.to_nalgebra(),
        h,
        r: Matrix3::identity() * (std * std),
    }
}

/// The estimated yaw `ψ̂ = atan2(C₂₁, C₁₁)`.
pub fn yaw(f: &Filter) -> f64 {
    let c = f.c_nb();
    c[(1, 0)].atan2(c[(0, 0)])
}

/// Heading `ψ̃ = ψ + b_ψ + a_ψ sin ψ + c_ψ cos ψ + w` (true heading; the AHRS's magnetic heading
/// plus the declination). Derived from `ψ = atan2(C₂₁, C₁₁)` with
/// `δC = [φ×] Ĉ`: `δψ = φ_D − C₃₁ (C₁₁ φ_N + C₂₁ φ_E) / (C₁₁² + C₂₁²)`
/// (`= φ_D + tan θ (cos ψ φ_N + sin ψ φ_E)`). `None` within 0.6° of
/// vertical pitch, where the heading is not defined.
pub fn heading(f: &Filter, z: f64, std: f64) -> Option<Measurement<1>> {
    let c = f.c_nb();
    let (c11, c21, c31) = (c[(0, 0)], c[(1, 0)], c[(2, 0)]);
    let d = c11 * c11 + c21 * c21;
    if !(d > 1e-4) {
        return None;
    }
    let psi = yaw(f);
    let (sin, cos) = psi.sin_cos();
    // ∂ẑ/∂ψ, the deviation's slope included.
    let g = 1.0 + f.dev[0] * cos - f.dev[1] * sin;
    let mut h = SMatrix::<f64, 1, N>::zeros();
    h[(0, ATT)] = -g * c31 * c11 / d;
    h[(0, ATT + 1)] = -g * c31 * c21 / d;
    h[(0, ATT + 2)] = g;
    h[(0, BH)] = 1.0;
    h[(0, DA)] = sin;
    h[(0, DC)] = cos;
    Some(Measurement {
        nu: Vector1::new(wrap_pi(z - psi - f.bh - f.dev[0] * sin - f.dev[1] * cos)),
        h,
        r: Matrix1::new(std * std),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ains::ekf::model::{Cov, ErrorState};
    use crate::ains::ekf::params::EkfParams;
    use crate::frames::{Rotation, Vector};
    use crate::strapdown::StrapdownState;
    use nalgebra::UnitQuaternion;

    fn filter(q: UnitQuaternion<f64>, v: Vector3<f64>, w: Vector3<f64>) -> Filter {
        Filter {
            nav: StrapdownState::at_depth(
                Rotation::from_nalgebra(q),
                Vector::from_nalgebra(v),
                0.6,
                -0.1,
                10.0,
            ),
            ba: Vector3::zeros(),
            bg: Vector3::zeros(),
            bh: 0.01,
            dev: [0.002, -0.003],
            omega_b: w,
            manoeuvre: Default::default(),
            p: Cov::identity(),
            block: Default::default(),
        }
    }

    /// `ẑ(x̂ ⊕ δx) − ẑ(x̂) ≈ H δx` for a small `δx` on every state the
    /// measurement depends on (the truth built from the error-state
    /// definitions: `C = exp(φ) Ĉ`, `v = v̂ + δv`, `ω = ω̂ − δb_g`, `b = b̂ + δb`).
    #[test]
    fn jacobians_match_finite_differences() {
        let cfg = EkfParams {
            dvl_lever_arm_m: [0.5, 0.1, 0.2],
            dvl_misalignment_rad: [0.01, 0.02, 0.03],
            ..Default::default()
        }
        .validate()
        .expect("valid");
        let q = crate::attitude::from_euler(0.1, 0.2, 1.0);
        let (v, w) = (Vector3::new(1.0, 0.5, 0.1), Vector3::new(0.01, 0.02, 0.3));
        let est = filter(q, v, w);
        let eps = 1e-6;
        for i in 0..N {
            let mut dx = ErrorState::zeros();
            dx[i] = eps;
            let phi = Vector3::new(dx[ATT], dx[ATT + 1], dx[ATT + 2]);
            let mut tru = filter(
                UnitQuaternion::from_scaled_axis(phi) * q,
                v + Vector3::new(dx[VEL], dx[VEL + 1], dx[VEL + 2]),
                w - Vector3::new(dx[BG], dx[BG + 1], dx[BG + 2]),
            );
            tru.bh += dx[BH];
            tru.dev[0] += dx[DA];
            tru.dev[1] += dx[DC];
            let z = Vector3::zeros();
            let (a, b) = (dvl(&est, &cfg, &z), dvl(&tru, &cfg, &z));
            let fd = (a.nu - b.nu) / eps; // ν = z − ẑ
            for r in 0..3 {
                assert!(
                    (fd[r] - a.h[(r, i)]).abs() < 1e-5,
                    "dvl H[{r}][{i}]: {fd} vs {}",
                    a.h
                );
            }
            let (a, b) = (
                heading(&est, 0.0, 0.01).expect("defined"),
                heading(&tru, 0.0, 0.01).expect("defined"),
            );
            let fd = (a.nu[0] - b.nu[0]) / eps;
            assert!(
                (fd - a.h[(0, i)]).abs() < 1e-5,
                "heading H[{i}]: {fd} vs {}",
                a.h[(0, i)]
            );
        }
        // The lever arm's rotation term: at rest, turning at 0.3 rad/s, a DVL
        // 0.5 m forward sees 0.15 m/s to starboard (misalignment aside).
        let cfg = EkfParams {
            dvl_lever_arm_m: [0.5, 0.0, 0.0],
            ..Default::default()
        }
        .validate()
        .expect("valid");
        let f = filter(q, Vector3::zeros(), Vector3::new(0.0, 0.0, 0.3));
        let m = dvl(&f, &cfg, &Vector3::new(0.0, 0.15, 0.0));
        assert!(m.nu.norm() < 1e-12, "{}", m.nu);
        let back = dvl_velocity_ned(&f, &cfg, &Vector3::new(0.0, 0.15, 0.0));
        assert!(back.norm() < 1e-12);
    }
}
