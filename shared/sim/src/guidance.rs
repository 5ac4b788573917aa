//! Guidance and control for a [`WaypointMission`]: line-of-sight (LOS) path
//! following with a lookahead distance, a heading controller commanding yaw rate
//! and a depth controller commanding pitch.
//!
//! - LOS (Fossen 2011, "Handbook of Marine Craft Hydrodynamics and Motion
//!   Control", §10.3.2, lookahead-based steering): on the leg from the previous
//!   waypoint `p₀` to the current one `p₁`, with along-track distance `s` and
//!   cross-track error `e`, the desired course is
//!   `χ_d = χ_leg - atan(e / Δ)`, `Δ` the lookahead distance.
//! - Crab: the heading that makes the velocity over ground point along `χ_d` in
//!   the (truth) current `c`: `ψ_c = χ_d - asin(c_⊥ / u_h)`, `c_⊥` the current
//!   across `χ_d`, `u_h` the horizontal speed through the water.
//! - Heading: `r_c = k_ψ wrap(ψ_c - ψ)`, clamped to ±`r_max` by the vehicle.
//! - Depth: `θ_c = -k_z (d_c - d)`, clamped to ±`θ_max` (nose down to go deeper).
//! - A waypoint is reached when within the acceptance radius or when the
//!   along-track distance passes the leg's end.
//! - After the last waypoint the vehicle holds its course, climbs to the surface
//!   (depth command 0) and, within [`Guidance::surface_depth_m`] of it, stops the
//!   propeller and floats.
//!
//! Gains are our choice: with the vehicle's `τ_r` = 1 s, `k_ψ` = 0.5 1/s gives a
//! heading loop damping of 0.71; `k_z` = 0.1 rad/m with the pitch loop gives a
//! ~50° phase margin at 1.5 m/s.

use nalgebra::Vector3;
use nauta_estimation::attitude::wrap_pi;

use crate::mission::WaypointMission;
use crate::vehicle::{Commands, VehicleState};

/// What the guidance is doing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// Following the leg to waypoint `index`.
    Transit {
        /// Index of the waypoint being steered to.
        index: usize,
    },
    /// Past the last waypoint, climbing.
    Surfacing,
    /// At the surface, propeller stopped.
    Done,
}

/// Guidance gains and thresholds (our choice; see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GuidanceParams {
    /// LOS lookahead distance `Δ`, m (20 m).
    pub lookahead_m: f64,
    /// Waypoint acceptance radius, m (10 m).
    pub acceptance_radius_m: f64,
    /// Heading gain `k_ψ`, 1/s (0.5).
    pub heading_gain_per_s: f64,
    /// Depth gain `k_z`, rad/m (0.1).
    pub depth_gain_rad_per_m: f64,
    /// Depth below which surfacing counts as done, m (0.3 m).
    pub surface_depth_m: f64,
}

impl Default for GuidanceParams {
    fn default() -> Self {
        Self {
            lookahead_m: 20.0,
            acceptance_radius_m: 10.0,
            heading_gain_per_s: 0.5,
            depth_gain_rad_per_m: 0.1,
            surface_depth_m: 0.3,
        }
    }
}

/// LOS guidance with heading and depth control along a [`WaypointMission`].
#[derive(Debug, Clone, PartialEq)]
pub struct Guidance {
    mission: WaypointMission,
    params: GuidanceParams,
    phase: Phase,
    hold_course_rad: f64,
    last_speed_m_s: f64,
}

impl Guidance {
    /// Starts on the leg to the first waypoint (an empty route surfaces at once).
    pub fn new(mission: WaypointMission, params: GuidanceParams) -> Self {
        let phase = if mission.waypoints.is_empty() {
            Phase::Surfacing
        } else {
            Phase::Transit { index: 0 }
        };
        let hold = mission.start_yaw_rad;
        let speed = mission.waypoints.first().map_or(0.0, |w| w.speed_m_s);
        Self {
            mission,
            params,
            phase,
            hold_course_rad: hold,
            last_speed_m_s: speed,
        }
    }

    /// The current phase.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// The mission.
    pub fn mission(&self) -> &WaypointMission {
        &self.mission
    }

    /// Depth under which surfacing is complete, m.
    pub fn surface_depth_m(&self) -> f64 {
        self.params.surface_depth_m
    }

    fn leg(&self, index: usize) -> ((f64, f64), (f64, f64)) {
        let w = &self.mission.waypoints;
        let p0 = if index == 0 {
            (0.0, 0.0)
        } else {
            (w[index - 1].north_m, w[index - 1].east_m)
        };
        (p0, (w[index].north_m, w[index].east_m))
    }

    /// Commands for state `s` at local position (`north_m`, `east_m`) in current
    /// `current_ned`; advances the phase when a waypoint is reached.
    pub fn command(
        &mut self,
        s: &VehicleState,
        north_m: f64,
        east_m: f64,
        current_ned: &Vector3<f64>,
    ) -> Commands {
        let p = self.params;
        // Advance past reached waypoints.
        while let Phase::Transit { index } = self.phase {
            let ((n0, e0), (n1, e1)) = self.leg(index);
            let (dn, de) = (n1 - n0, e1 - e0);
            let len = dn.hypot(de);
            let along = if len > 0.0 {
                ((north_m - n0) * dn + (east_m - e0) * de) / len
            } else {
                0.0
            };
            let dist = (n1 - north_m).hypot(e1 - east_m);
            if dist < p.acceptance_radius_m || along >= len {
                if len > 0.0 {
                    self.hold_course_rad = de.atan2(dn);
                }
                self.phase = if index + 1 < self.mission.waypoints.len() {
                    Phase::Transit { index: index + 1 }
                } else {
                    Phase::Surfacing
                };
            } else {
                break;
            }
        }
        if self.phase == Phase::Surfacing && s.depth_m <= p.surface_depth_m {
            self.phase = Phase::Done;
        }
        let (course, depth_cmd, speed) = match self.phase {
            Phase::Transit { index } => {
                let ((n0, e0), (n1, e1)) = self.leg(index);
                let chi_leg = (e1 - e0).atan2(n1 - n0);
                let (sl, cl) = chi_leg.sin_cos();
                let cross = -(north_m - n0) * sl + (east_m - e0) * cl;
                let w = self.mission.waypoints[index];
                self.last_speed_m_s = w.speed_m_s;
                (
                    chi_leg - (cross / p.lookahead_m).atan(),
                    w.depth_m,
                    w.speed_m_s,
                )
            }
            Phase::Surfacing => (self.hold_course_rad, 0.0, self.last_speed_m_s),
            Phase::Done => {
                return Commands::default();
            }
        };
        // Crab into the current.
        let u_h = (s.speed_m_s * s.pitch_rad.cos()).max(0.3);
        let (sc, cc) = course.sin_cos();
        let c_perp = -current_ned.x * sc + current_ned.y * cc;
        let heading_cmd = course - (c_perp / u_h).clamp(-0.9, 0.9).asin();
        Commands {
            speed_m_s: speed,
            yaw_rate_rad_s: p.heading_gain_per_s * wrap_pi(heading_cmd - s.yaw_rad),
            pitch_rad: -p.depth_gain_rad_per_m * (depth_cmd - s.depth_m),
        }
    }
}
