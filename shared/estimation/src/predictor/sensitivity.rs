//! Paper 002 eqs. 14-17: the first-order velocity error of dead reckoning,
//! `δv_n = J(v_b, Θ) [δv_b; δΘ]`, in its four forms.
//!
//! `J` is 3×6: rows north, east, down; columns `δv_x, δv_y, δv_z` (the DVL's
//! body-frame velocity errors, m/s) then `δφ, δθ, δψ` (the attitude errors,
//! rad). The paper writes each component out; the functions below keep its
//! terms one for one. Eq. 14 is exact to first order: its `δv_b` columns are
//! the rows of `R_b^n(Θ)` (eq. 1) and its `δΘ` columns `∂R_b^n/∂Θ · v_b`
//! (checked against a numerical derivative of eq. 1 in the tests below; no
//! misprint was found in the paper's text of eqs. 14-17). Eqs. 15, 16 and 17
//! are eq. 14 with `φ = 0`, with `θ = 0`, and with both, as the paper derives
//! them (eq. 17 drops the `δv_z` terms of the horizontal rows, which vanish
//! there).

use serde::Deserialize;

/// Which of paper 002's forms gives the sensitivities.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Form {
    /// Eq. 14: the general first-order form.
    Eq14,
    /// Eq. 15: negligible roll (`φ ≈ 0`).
    Eq15,
    /// Eq. 16: horizontal plane (`θ ≈ 0`).
    Eq16,
    /// Eq. 17: both (`φ ≈ θ ≈ 0`), the lean form the paper recommends for
    /// embedded use; the default.
    #[default]
    Eq17,
}

/// `J`: rows N, E, D; columns `δv_x, δv_y, δv_z, δφ, δθ, δψ`.
pub type Sensitivity = [[f64; 6]; 3];

/// The sensitivities of `form` at body velocity `v_b` (m/s, FRD) and Euler
/// angles roll `φ`, pitch `θ`, yaw `ψ` (rad, ZYX): the paper's `v_b ≈ v̂_b`,
/// `Θ ≈ Θ̂` (the measured values stand for the true ones).
pub fn sensitivity(form: Form, v_b: [f64; 3], roll: f64, pitch: f64, yaw: f64) -> Sensitivity {
    match form {
        Form::Eq14 => eq14(v_b, roll, pitch, yaw),
        Form::Eq15 => eq15(v_b, pitch, yaw),
        Form::Eq16 => eq16(v_b, roll, yaw),
        Form::Eq17 => eq17(v_b, yaw),
    }
}

/// Paper 002 eq. 14.
fn eq14([vx, vy, vz]: [f64; 3], phi: f64, theta: f64, psi: f64) -> Sensitivity {
    let (sf, cf) = phi.sin_cos();
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = psi.sin_cos();
    [
        [
            ct * cp,
            cp * st * sf - cf * sp,
            cf * cp * st + sf * sp,
            (cf * cp * st + sf * sp) * vy + (cf * sp - cp * st * sf) * vz,
            -cp * st * vx + ct * cp * sf * vy + ct * cf * cp * vz,
            -ct * sp * vx + (-cf * cp - st * sf * sp) * vy + (cp * sf - cf * st * sp) * vz,
        ],
        [
            ct * sp,
            st * sf * sp + cf * cp,
            cf * st * sp - cp * sf,
            (cf * st * sp - cp * sf) * vy + (-cf * cp - st * sf * sp) * vz,
            -st * sp * vx + ct * sf * sp * vy + ct * cf * sp * vz,
            ct * cp * vx + (cp * st * sf - cf * sp) * vy + (sf * sp + cf * cp * st) * vz,
        ],
        [
            -st,
            ct * sf,
            ct * cf,
            ct * cf * vy - ct * sf * vz,
            -ct * vx - st * sf * vy - cf * st * vz,
            0.0,
        ],
    ]
}

/// Paper 002 eq. 15 (negligible roll).
fn eq15([vx, vy, vz]: [f64; 3], theta: f64, psi: f64) -> Sensitivity {
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = psi.sin_cos();
    [
        [
            ct * cp,
            -sp,
            cp * st,
            cp * st * vy + sp * vz,
            -cp * st * vx + ct * cp * vz,
            -ct * sp * vx - cp * vy - st * sp * vz,
        ],
        [
            ct * sp,
            cp,
            st * sp,
            st * sp * vy - cp * vz,
            -st * sp * vx + ct * sp * vz,
            ct * cp * vx - sp * vy + cp * st * vz,
        ],
        [-st, 0.0, ct, ct * vy, -ct * vx - st * vz, 0.0],
    ]
}

/// Paper 002 eq. 16 (horizontal plane).
fn eq16([vx, vy, vz]: [f64; 3], phi: f64, psi: f64) -> Sensitivity {
    let (sf, cf) = phi.sin_cos();
    let (sp, cp) = psi.sin_cos();
    [
        [
            cp,
            -cf * sp,
            sf * sp,
            sf * sp * vy + cf * sp * vz,
            cp * sf * vy + cf * cp * vz,
            -sp * vx - cf * cp * vy + cp * sf * vz,
        ],
        [
            sp,
            cf * cp,
            -cp * sf,
            -cp * sf * vy - cf * cp * vz,
            sf * sp * vy + cf * sp * vz,
            cp * vx - cf * sp * vy + sf * sp * vz,
        ],
        [0.0, sf, cf, cf * vy - sf * vz, -vx, 0.0],
    ]
}

/// Paper 002 eq. 17 (negligible roll, horizontal plane).
fn eq17([vx, vy, vz]: [f64; 3], psi: f64) -> Sensitivity {
    let (sp, cp) = psi.sin_cos();
    [
        [cp, -sp, 0.0, sp * vz, cp * vz, -sp * vx - cp * vy],
        [sp, cp, 0.0, -cp * vz, sp * vz, cp * vx - sp * vy],
        [0.0, 0.0, 1.0, vy, -vx, 0.0],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frames::{Frd, Rotation, Vector};

    /// Eq. 1: `R_b^n(Θ) v_b`.
    fn v_n(v_b: [f64; 3], e: [f64; 3]) -> [f64; 3] {
        (Rotation::<Frd, _>::from_euler(e[0], e[1], e[2]) * Vector::<Frd>::from_array(v_b))
            .to_array()
    }

    /// The numerical Jacobian of eq. 1 (central differences).
    fn numerical(v_b: [f64; 3], e: [f64; 3]) -> Sensitivity {
        let h = 1e-6;
        let mut j = [[0.0; 6]; 3];
        for c in 0..6 {
            let (mut vp, mut vm, mut ep, mut em) = (v_b, v_b, e, e);
            if c < 3 {
                vp[c] += h;
                vm[c] -= h;
            } else {
                ep[c - 3] += h;
                em[c - 3] -= h;
            }
            let (a, b) = (v_n(vp, ep), v_n(vm, em));
            for r in 0..3 {
                j[r][c] = (a[r] - b[r]) / (2.0 * h);
            }
        }
        j
    }

    fn close(a: &Sensitivity, b: &Sensitivity, tol: f64) -> bool {
        a.iter()
            .flatten()
            .zip(b.iter().flatten())
            .all(|(x, y)| (x - y).abs() < tol)
    }

    const CASES: [([f64; 3], [f64; 3]); 4] = [
        ([1.2, 0.1, -0.05], [0.1, -0.2, 0.7]),
        ([0.8, -0.3, 0.2], [-0.4, 0.3, 2.5]),
        ([1.5, 0.0, 0.0], [0.0, 0.0, -1.9]),
        ([-0.2, 0.6, 0.4], [0.9, -1.1, 4.0]),
    ];

    #[test]
    fn eq14_is_the_first_order_derivative_of_eq1() {
        for (v, e) in CASES {
            let j = sensitivity(Form::Eq14, v, e[0], e[1], e[2]);
            assert!(close(&j, &numerical(v, e), 1e-8), "{v:?} {e:?}: {j:?}");
        }
    }

    #[test]
    fn eqs_15_to_17_are_eq14_with_roll_pitch_or_both_zero() {
        for (v, e) in CASES {
            let [phi, theta, psi] = e;
            let e15 = sensitivity(Form::Eq15, v, phi, theta, psi);
            assert!(close(&e15, &eq14(v, 0.0, theta, psi), 1e-14), "15");
            let e16 = sensitivity(Form::Eq16, v, phi, theta, psi);
            assert!(close(&e16, &eq14(v, phi, 0.0, psi), 1e-14), "16");
            let e17 = sensitivity(Form::Eq17, v, phi, theta, psi);
            let mut e14 = eq14(v, 0.0, 0.0, psi);
            // Eq. 17 leaves out the horizontal δv_z terms, zero at φ = θ = 0.
            e14[0][2] = 0.0;
            e14[1][2] = 0.0;
            assert!(close(&e17, &e14, 1e-14), "17");
            // With roll and pitch zero, all four agree.
            let all = [Form::Eq14, Form::Eq15, Form::Eq16, Form::Eq17]
                .map(|f| sensitivity(f, v, 0.0, 0.0, psi));
            for j in &all[1..] {
                assert!(close(j, &all[0], 1e-14));
            }
        }
    }
}
