//! The dead-reckoning model between two filter steps (paper 003 §V-B;
//! paper 004 eqs. 1-4, eq. 3's second row read `w_y` as eq. 2 and paper
//! 003 have it) and its exact discretisation over one step of held inputs.
//!
//! With the inputs held over `[t_i, t_{i+1}]` (zero-order hold: shaft
//! speed, pitch and heading from the samples before `t_i`), eq. 3 is
//!
//! ```text
//! Ė = F(E) = A E + u,   A = ∂F/∂E (constant over the step)
//! ```
//!
//! - `velocity_source = "propeller"`, `k` known (4 states `[x, y, w_x, w_y]`):
//!   `u = k a`, `a = ω cos θ (cos ψ, sin ψ)` (eqs. 1-2), `A` couples `w` into
//!   the position;
//! - `k` estimated (5 states `[x, y, w_x, w_y, k]`): `u = 0` and `A` has
//!   `∂ẋ/∂k = a` too (eq. 3 is then bilinear, exact in `E` for held inputs);
//! - `velocity_source = "dvl"` (4 states): `u = a`, the DVL's velocity over
//!   the ground; `(w_x, w_y)` is then what that velocity misses, mostly the
//!   AHRS heading's error times the speed (a random walk as the current is:
//!   without it a 2° heading bias drifts the estimate by 0.04 m/s), and
//!   `A` couples it as it couples the current.
//!
//! `A` is nilpotent (`A² = 0`: only the position rows are non-zero, and
//! only columns of the other states), so the transition matrix of
//! `ż = A z` is exactly `φ(τ) = I + A τ`; paper 004's `b_i` (the solution at
//! `t_{i+1}` of `ḃ = A b + F − A E`, `b(t_i) = 0`) is exactly `u Δt` (`A u = 0`);
//! and `Q_i = ∫ φ(τ) Q φ(τ)ᵀ dτ = Q Δt + (A Q + Q Aᵀ) Δt²/2 + A Q Aᵀ Δt³/3`.
//! The prediction `E⁻ = φ E + b`, `P⁻ = φ P φᵀ + Q_i` is thus the exact
//! solution of eqs. 3-4 over the step, and what the smoother needs (paper
//! 004 eqs. 7-9) comes out of it unchanged.

use nalgebra::{SMatrix, SVector};

/// Which of the three forms of eq. 3 the filter runs (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Dynamics {
    /// Propeller with a known `k`, m/rad.
    Propeller {
        /// `k`, m/rad.
        k: f64,
    },
    /// Propeller with `k` the fifth state.
    PropellerEstimatedK,
    /// A velocity over the ground (DVL bottom track); `w` is its error.
    OverGround,
}

/// The inputs held over one step: `a`, the velocity per unit of `k`
/// (propeller: `ω cos θ (cos ψ, sin ψ)`, rad/s) or the velocity over the
/// ground (DVL, m/s), north and east.
pub type Basis = [f64; 2];

/// The model of eqs. 3-4: the dynamics and `Q`'s diagonal (continuous, per
/// second): position, position, current, current, `k`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Model {
    /// The form of eq. 3.
    pub dynamics: Dynamics,
    /// `Q`'s diagonal (eq. 4).
    pub q: [f64; 5],
}

/// One step's discretisation: `φ`, `b` and `Q_i` (paper 004 eqs. 7-9).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Discrete<const N: usize> {
    /// `φ_i = φ(t_{i+1}, t_i) = I + A Δt`.
    pub phi: SMatrix<f64, N, N>,
    /// `b_i = u Δt`.
    pub b: SVector<f64, N>,
    /// `Q_i`.
    pub q: SMatrix<f64, N, N>,
}

impl Model {
    /// Whether the current `(w_x, w_y)` moves the position (in every form
    /// of eq. 3; kept as a question for the range model's sake).
    pub fn current_moves_position(&self) -> bool {
        true
    }

    /// The factor of `a` in the velocity: `k`, the state's `k`, or 1.
    pub fn scale<const N: usize>(&self, x: &SVector<f64, N>) -> f64 {
        match self.dynamics {
            Dynamics::Propeller { k } => k,
            Dynamics::PropellerEstimatedK if N > 4 => x[4],
            Dynamics::PropellerEstimatedK | Dynamics::OverGround => 1.0,
        }
    }

    /// `A = ∂F/∂E` for the held `a` (eq. 4's `∂F/∂E`).
    pub fn jacobian<const N: usize>(&self, a: Basis) -> SMatrix<f64, N, N> {
        let mut j = SMatrix::<f64, N, N>::zeros();
        if self.current_moves_position() {
            j[(0, 2)] = 1.0;
            j[(1, 3)] = 1.0;
        }
        if matches!(self.dynamics, Dynamics::PropellerEstimatedK) && N > 4 {
            j[(0, 4)] = a[0];
            j[(1, 4)] = a[1];
        }
        j
    }

    /// `u`: what eq. 3 adds besides `A E`.
    fn input<const N: usize>(&self, a: Basis) -> SVector<f64, N> {
        let mut u = SVector::<f64, N>::zeros();
        let s = match self.dynamics {
            Dynamics::Propeller { k } => k,
            Dynamics::OverGround => 1.0,
            Dynamics::PropellerEstimatedK => 0.0,
        };
        u[0] = s * a[0];
        u[1] = s * a[1];
        u
    }

    /// The exact discretisation over `dt_s` with `a` held (module docs).
    pub fn discrete<const N: usize>(&self, a: Basis, dt_s: f64) -> Discrete<N> {
        let j = self.jacobian::<N>(a);
        let mut q = SMatrix::<f64, N, N>::zeros();
        for i in 0..N {
            q[(i, i)] = self.q[i];
        }
        let phi = SMatrix::<f64, N, N>::identity() + j * dt_s;
        let b = self.input::<N>(a) * dt_s;
        let jq = j * q;
        let qd = q * dt_s
            + (jq + jq.transpose()) * (0.5 * dt_s * dt_s)
            + jq * j.transpose() * (dt_s * dt_s * dt_s / 3.0);
        Discrete { phi, b, q: qd }
    }

    /// The velocity `F(E)`'s position rows at `x` with `a` held, north and
    /// east, m/s (eqs. 1-2).
    pub fn velocity<const N: usize>(&self, x: &SVector<f64, N>, a: Basis) -> [f64; 2] {
        let s = self.scale(x);
        let w = if self.current_moves_position() {
            [x[2], x[3]]
        } else {
            [0.0, 0.0]
        };
        [s * a[0] + w[0], s * a[1] + w[1]]
    }
}

/// Eqs. 1-2's `a = ω cos θ (cos ψ, sin ψ)`: shaft speed `ω` (rad/s), pitch
/// `θ` and true heading `ψ` (rad).
pub fn propeller_basis(shaft_rad_s: f64, pitch_rad: f64, heading_rad: f64) -> Basis {
    let (s, c) = heading_rad.sin_cos();
    let h = shaft_rad_s * pitch_rad.cos();
    [h * c, h * s]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn propeller() -> Model {
        Model {
            dynamics: Dynamics::Propeller { k: 0.01 },
            q: [0.1, 0.1, 1e-4, 1e-4, 0.0],
        }
    }

    /// `φ`, `b`, `Q_i` against a fine numerical integration of eqs. 3-4.
    #[test]
    fn the_discretisation_is_the_solution_of_eqs_3_and_4() {
        for (model, n5) in [
            (propeller(), false),
            (
                Model {
                    dynamics: Dynamics::PropellerEstimatedK,
                    q: [0.1, 0.1, 1e-4, 1e-4, 1e-6],
                },
                true,
            ),
        ] {
            let a = propeller_basis(120.0, 0.1, 0.7);
            let dt = 0.1;
            macro_rules! check {
                ($n:literal) => {{
                    let d = model.discrete::<$n>(a, dt);
                    let mut x = SVector::<f64, $n>::from_fn(|i, _| 1.0 + i as f64 * 0.01);
                    let mut p = SMatrix::<f64, $n, $n>::identity();
                    let x_exact = d.phi * x + d.b;
                    let p_exact = d.phi * p * d.phi.transpose() + d.q;
                    let jac = model.jacobian::<$n>(a);
                    let mut qc = SMatrix::<f64, $n, $n>::zeros();
                    for i in 0..$n {
                        qc[(i, i)] = model.q[i];
                    }
                    let steps = 10_000;
                    let h = dt / steps as f64;
                    for _ in 0..steps {
                        let v = model.velocity(&x, a);
                        x[0] += v[0] * h;
                        x[1] += v[1] * h;
                        // Ṗ = A P + P Aᵀ + Q (eq. 4), midpoint rule.
                        let k1 = jac * p + p * jac.transpose() + qc;
                        let pm = p + k1 * (0.5 * h);
                        p += (jac * pm + pm * jac.transpose() + qc) * h;
                    }
                    assert!((x - x_exact).norm() < 1e-9, "{}", (x - x_exact).norm());
                    assert!((p - p_exact).norm() < 1e-9, "{}", (p - p_exact).norm());
                }};
            }
            if n5 {
                check!(5);
            } else {
                check!(4);
            }
        }
    }

    #[test]
    fn over_ground_the_velocity_is_the_input() {
        let m = Model {
            dynamics: Dynamics::OverGround,
            q: [0.1, 0.1, 0.0, 0.0, 0.0],
        };
        let d = m.discrete::<4>([1.0, -2.0], 0.5);
        assert_eq!((d.b[0], d.b[1]), (0.5, -1.0));
        assert_eq!((d.phi[(0, 2)], d.phi[(1, 3)]), (0.5, 0.5));
    }
}
