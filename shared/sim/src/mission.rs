//! Missions: waypoint routes with depth and speed set-points, and the scripted
//! attitude motions of paper 000's attitude tests; the builders of DESIGN §10's
//! scenarios (`survey`, `lbl`, `dr`).
//!
//! Waypoints are in a local north/east frame at an [`Origin`] (the mission's
//! start point at the surface): the exact local tangent plane of
//! [`nauta_estimation::local`], the one every tool of nauta uses to place a
//! local position; the truth itself is integrated on the ellipsoid.
//!
//! Every waypoint mission starts at rest at the origin at the surface, dives
//! towards the first waypoint's depth and, after the last waypoint, climbs to the
//! surface and stops ([`crate::guidance`]).

use nauta_estimation::local::{self, LocalTangentPlane};

/// The mission's local origin, rad.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Origin {
    /// Geodetic latitude, rad.
    pub lat_rad: f64,
    /// Longitude, rad.
    pub lon_rad: f64,
}

impl Origin {
    /// An origin from degrees.
    pub fn from_degrees(lat_deg: f64, lon_deg: f64) -> Self {
        Self {
            lat_rad: lat_deg.to_radians(),
            lon_rad: lon_deg.to_radians(),
        }
    }

    /// Off Lisbon / Sesimbra (38.6° N, 9.3° W), the default operating area (our choice).
    pub fn lisbon() -> Self {
        Self::from_degrees(38.6, -9.3)
    }

    /// The exact local tangent plane at the origin (at the sea surface);
    /// `None` when the origin is not a geodetic position (a latitude beyond
    /// ±90°, a non-finite value).
    pub fn plane(&self) -> Option<LocalTangentPlane> {
        LocalTangentPlane::new(self.lat_rad, self.lon_rad, 0.0).ok()
    }

    /// Local (north, east) of a geodetic position, m (the exact plane; NaN
    /// from an origin that is not a position, which every check refuses).
    pub fn to_local(&self, lat_rad: f64, lon_rad: f64) -> (f64, f64) {
        local::north_east_of(self.lat_rad, self.lon_rad, lat_rad, lon_rad)
    }

    /// Geodetic (lat, lon) of a local (north, east), rad (the exact plane;
    /// NaN as [`Origin::to_local`]).
    pub fn to_geodetic(&self, north_m: f64, east_m: f64) -> (f64, f64) {
        local::geodetic_of(self.lat_rad, self.lon_rad, north_m, east_m)
    }
}

/// One waypoint: where to go, at what depth and speed on the leg that ends here.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Waypoint {
    /// North of the origin, m.
    pub north_m: f64,
    /// East of the origin, m.
    pub east_m: f64,
    /// Depth set-point on the leg to this waypoint, m.
    pub depth_m: f64,
    /// Speed through the water on the leg to this waypoint, m/s.
    pub speed_m_s: f64,
}

impl Waypoint {
    /// A waypoint.
    pub fn new(north_m: f64, east_m: f64, depth_m: f64, speed_m_s: f64) -> Self {
        Self {
            north_m,
            east_m,
            depth_m,
            speed_m_s,
        }
    }
}

/// A waypoint route from the origin (at rest at the surface).
#[derive(Debug, Clone, PartialEq)]
pub struct WaypointMission {
    /// Scenario name.
    pub name: String,
    /// Start point and local frame.
    pub origin: Origin,
    /// Initial heading, rad.
    pub start_yaw_rad: f64,
    /// Time floating still at the surface before the vehicle starts, s: the
    /// static period an attitude alignment needs (paper 000 averages 400
    /// samples, 4 s at 100 Hz). Propeller stopped, no roll oscillation.
    pub still_s: f64,
    /// The route.
    pub waypoints: Vec<Waypoint>,
}

impl WaypointMission {
    /// Horizontal length of the route from the origin through every waypoint, m.
    pub fn route_length_m(&self) -> f64 {
        let mut prev = (0.0, 0.0);
        let mut sum = 0.0;
        for w in &self.waypoints {
            sum += (w.north_m - prev.0).hypot(w.east_m - prev.1);
            prev = (w.north_m, w.east_m);
        }
        sum
    }

    /// Waypoints given in latitude/longitude (rad) instead of north/east.
    pub fn from_geodetic(
        name: &str,
        origin: Origin,
        start_yaw_rad: f64,
        points: &[(f64, f64, f64, f64)],
    ) -> Self {
        let waypoints = points
            .iter()
            .map(|&(lat, lon, depth, speed)| {
                let (n, e) = origin.to_local(lat, lon);
                Waypoint::new(n, e, depth, speed)
            })
            .collect();
        Self {
            name: name.to_owned(),
            origin,
            start_yaw_rad,
            still_s: 0.0,
            waypoints,
        }
    }
}

/// Paper 000's attitude test motions (§IV-A: "static, pitch and roll movements and
/// yaw movement"; the paper gives no amplitudes or periods, these are our choice).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AttitudeMotion {
    /// Held still.
    Still,
    /// Pitch and roll rocking: `φ = A_φ sin(2πt/T_φ)`, `θ = A_θ sin(2πt/T_θ)`.
    Rocking {
        /// Roll amplitude, rad.
        roll_amplitude_rad: f64,
        /// Roll period, s.
        roll_period_s: f64,
        /// Pitch amplitude, rad.
        pitch_amplitude_rad: f64,
        /// Pitch period, s.
        pitch_period_s: f64,
    },
    /// Yaw turns back and forth: `ψ = ψ₀ + A_ψ sin(2πt/T_ψ)`.
    YawTurns {
        /// Yaw amplitude, rad.
        amplitude_rad: f64,
        /// Period, s.
        period_s: f64,
    },
}

impl AttitudeMotion {
    /// Rocking of ±20° roll every 6 s and ±15° pitch every 8 s (our choice; a hand
    /// rocking an IMU on a table).
    pub fn rocking() -> Self {
        Self::Rocking {
            roll_amplitude_rad: 20f64.to_radians(),
            roll_period_s: 6.0,
            pitch_amplitude_rad: 15f64.to_radians(),
            pitch_period_s: 8.0,
        }
    }

    /// Yaw turns of ±90° every 20 s (peak 28°/s; our choice).
    pub fn yaw_turns() -> Self {
        Self::YawTurns {
            amplitude_rad: 90f64.to_radians(),
            period_s: 20.0,
        }
    }

    /// (roll, pitch, yaw offset) at `t_s`, rad.
    pub fn euler_at(&self, t_s: f64) -> (f64, f64, f64) {
        let w = |period: f64| (std::f64::consts::TAU * t_s / period).sin();
        match *self {
            Self::Still => (0.0, 0.0, 0.0),
            Self::Rocking {
                roll_amplitude_rad,
                roll_period_s,
                pitch_amplitude_rad,
                pitch_period_s,
            } => (
                roll_amplitude_rad * w(roll_period_s),
                pitch_amplitude_rad * w(pitch_period_s),
                0.0,
            ),
            Self::YawTurns {
                amplitude_rad,
                period_s,
            } => (0.0, 0.0, amplitude_rad * w(period_s)),
        }
    }
}

/// A stationary IMU moved through a scripted attitude.
#[derive(Debug, Clone, PartialEq)]
pub struct AttitudeMission {
    /// Scenario name.
    pub name: String,
    /// Where the IMU is.
    pub origin: Origin,
    /// Depth, m (0: on deck).
    pub depth_m: f64,
    /// Base heading `ψ₀`, rad.
    pub heading_rad: f64,
    /// The motion.
    pub motion: AttitudeMotion,
    /// Duration, s.
    pub duration_s: f64,
}

/// Anything the simulator can run.
#[derive(Debug, Clone, PartialEq)]
pub enum Mission {
    /// A vehicle following waypoints.
    Waypoints(WaypointMission),
    /// A stationary IMU with scripted attitude.
    Attitude(AttitudeMission),
}

impl Mission {
    /// Scenario name.
    pub fn name(&self) -> &str {
        match self {
            Self::Waypoints(m) => &m.name,
            Self::Attitude(m) => &m.name,
        }
    }

    /// The same mission with `still_s` of rest at the surface before the
    /// route starts (waypoint missions; an attitude script is unchanged).
    pub fn with_still_s(mut self, still_s: f64) -> Self {
        if let Self::Waypoints(w) = &mut self {
            w.still_s = still_s;
        }
        self
    }

    /// The origin.
    pub fn origin(&self) -> Origin {
        match self {
            Self::Waypoints(m) => m.origin,
            Self::Attitude(m) => m.origin,
        }
    }
}

/// The `survey` scenario's parameters (DESIGN §10; the numbers are our choice,
/// paper 000 gives none).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurveySpec {
    /// Number of parallel transects (6).
    pub legs: usize,
    /// Transect length, m (600).
    pub leg_length_m: f64,
    /// Spacing between transects, m (50).
    pub spacing_m: f64,
    /// Survey depth, m (15).
    pub depth_m: f64,
    /// Speed, m/s (1.5).
    pub speed_m_s: f64,
    /// Direction of the first transect, rad from north (0).
    pub heading_rad: f64,
}

impl Default for SurveySpec {
    /// 6 transects of 600 m, 50 m apart, at 15 m and 1.5 m/s: 3850 m of route,
    /// about 45 minutes with the dive and the surfacing.
    fn default() -> Self {
        Self {
            legs: 6,
            leg_length_m: 600.0,
            spacing_m: 50.0,
            depth_m: 15.0,
            speed_m_s: 1.5,
            heading_rad: 0.0,
        }
    }
}

/// A lawnmower from the origin: `legs` transects of `length` along `heading`,
/// stepping `spacing` to the right (starboard) of it.
fn lawnmower(
    legs: usize,
    length_m: f64,
    spacing_m: f64,
    depth_m: f64,
    speed_m_s: f64,
    heading_rad: f64,
) -> Vec<Waypoint> {
    let (s, c) = heading_rad.sin_cos();
    // Along-track unit (c, s), cross-track (to starboard) unit (-s, c).
    let at = |along: f64, across: f64| {
        Waypoint::new(
            along * c - across * s,
            along * s + across * c,
            depth_m,
            speed_m_s,
        )
    };
    let mut w = Vec::with_capacity(2 * legs);
    for i in 0..legs {
        let across = i as f64 * spacing_m;
        let (a0, a1) = if i % 2 == 0 {
            (0.0, length_m)
        } else {
            (length_m, 0.0)
        };
        if i > 0 {
            w.push(at(a0, across));
        }
        w.push(at(a1, across));
    }
    w
}

/// The `survey` scenario (paper 000's parallel transects; DESIGN §10).
pub fn survey(origin: Origin, spec: &SurveySpec) -> Mission {
    Mission::Waypoints(WaypointMission {
        name: "survey".into(),
        origin,
        start_yaw_rad: spec.heading_rad,
        still_s: 0.0,
        waypoints: lawnmower(
            spec.legs,
            spec.leg_length_m,
            spec.spacing_m,
            spec.depth_m,
            spec.speed_m_s,
            spec.heading_rad,
        ),
    })
}

/// The `lbl` scenario (papers 003/004; DESIGN §10): an Isurus-like vehicle at
/// 1.2 m/s and 10 m depth round a 500 m × 400 m box `laps` times and back up
/// its first side: 500 + 1800 `laps` m of route (2300 m, about 32 minutes,
/// for one lap; five laps, 9.5 km, are over two hours, paper 004's mission
/// length). The shape is our choice; paper 003 does not give the route.
pub fn lbl(origin: Origin, laps: u32) -> Mission {
    let (d, u) = (10.0, 1.2);
    let mut waypoints = vec![Waypoint::new(500.0, 0.0, d, u)];
    for _ in 0..laps.max(1) {
        waypoints.extend([
            Waypoint::new(500.0, 400.0, d, u),
            Waypoint::new(0.0, 400.0, d, u),
            Waypoint::new(0.0, 0.0, d, u),
            Waypoint::new(500.0, 0.0, d, u),
        ]);
    }
    Mission::Waypoints(WaypointMission {
        name: "lbl".into(),
        origin,
        start_yaw_rad: 0.0,
        still_s: 0.0,
        waypoints,
    })
}

/// Paper 002's three dead-reckoning manoeuvres (§4, fig. 10; its table gives
/// t₁ ≈ 11 min, d₁ ≈ 650 m; t₂ ≈ 49 min, d₂ ≈ 3543 m; t₃ ≈ 2 h 22 min,
/// d₃ ≈ 10752 m). The paper's plots are not in its text, so the shapes are our
/// approximation: a closed rectangle, then lawnmowers of matching length; the
/// speeds are distance / time (1.0, 1.2, 1.26 m/s). Depth 3 m (Pirajuba ran
/// shallow coastal missions; our choice).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DrManoeuvre {
    /// ≈ 650 m in ≈ 11 min: a 225 m × 100 m rectangle back to the start.
    One,
    /// ≈ 3.5 km in ≈ 49 min: 4 transects of 800 m, 100 m apart (3500 m).
    Two,
    /// ≈ 10.8 km in ≈ 2 h 22 min: 6 transects of 1700 m, 100 m apart (10700 m).
    Three,
}

/// The `dr` scenario, one of paper 002's manoeuvres ([`DrManoeuvre`]).
pub fn dr(origin: Origin, which: DrManoeuvre) -> Mission {
    let depth = 3.0;
    let (name, waypoints) = match which {
        DrManoeuvre::One => {
            let u = 1.0;
            (
                "dr1",
                vec![
                    Waypoint::new(225.0, 0.0, depth, u),
                    Waypoint::new(225.0, 100.0, depth, u),
                    Waypoint::new(0.0, 100.0, depth, u),
                    Waypoint::new(0.0, 0.0, depth, u),
                ],
            )
        }
        DrManoeuvre::Two => ("dr2", lawnmower(4, 800.0, 100.0, depth, 1.2, 0.0)),
        DrManoeuvre::Three => ("dr3", lawnmower(6, 1700.0, 100.0, depth, 1.26, 0.0)),
    };
    Mission::Waypoints(WaypointMission {
        name: name.into(),
        origin,
        start_yaw_rad: 0.0,
        still_s: 0.0,
        waypoints,
    })
}

/// Paper 000's attitude test motions, for `duration_s` at the surface heading
/// 30° (our choice).
pub fn attitude(origin: Origin, motion: AttitudeMotion, duration_s: f64) -> Mission {
    let name = match motion {
        AttitudeMotion::Still => "attitude-still",
        AttitudeMotion::Rocking { .. } => "attitude-rocking",
        AttitudeMotion::YawTurns { .. } => "attitude-yaw",
    };
    Mission::Attitude(AttitudeMission {
        name: name.into(),
        origin,
        depth_m: 0.0,
        heading_rad: 30f64.to_radians(),
        motion,
        duration_s,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn route(m: &Mission) -> f64 {
        match m {
            Mission::Waypoints(w) => w.route_length_m(),
            Mission::Attitude(_) => 0.0,
        }
    }

    #[test]
    fn builders_have_the_documented_lengths() {
        let o = Origin::lisbon();
        assert!((route(&survey(o, &SurveySpec::default())) - 3850.0).abs() < 1e-9);
        assert!((route(&lbl(o, 1)) - 2300.0).abs() < 1e-9);
        assert!((route(&lbl(o, 5)) - 9500.0).abs() < 1e-9);
        assert!((route(&dr(o, DrManoeuvre::One)) - 650.0).abs() < 1e-9);
        assert!((route(&dr(o, DrManoeuvre::Two)) - 3500.0).abs() < 1e-9);
        assert!((route(&dr(o, DrManoeuvre::Three)) - 10700.0).abs() < 1e-9);
    }

    #[test]
    fn local_and_geodetic_round_trip() {
        let o = Origin::lisbon();
        let (lat, lon) = o.to_geodetic(1234.5, -678.9);
        let (n, e) = o.to_local(lat, lon);
        assert!((n - 1234.5).abs() < 1e-9 && (e + 678.9).abs() < 1e-9);
        let m = WaypointMission::from_geodetic("x", o, 0.0, &[(lat, lon, 5.0, 1.0)]);
        assert!((m.waypoints[0].north_m - 1234.5).abs() < 1e-9);
    }

    #[test]
    fn lawnmower_shape() {
        let w = lawnmower(3, 100.0, 10.0, 5.0, 1.0, std::f64::consts::FRAC_PI_2);
        // Heading east: first transect east, then step south (starboard).
        assert_eq!(w.len(), 5);
        assert!((w[0].east_m - 100.0).abs() < 1e-12 && w[0].north_m.abs() < 1e-12);
        assert!((w[1].north_m + 10.0).abs() < 1e-12);
        assert!((w[2].east_m).abs() < 1e-12);
    }
}
