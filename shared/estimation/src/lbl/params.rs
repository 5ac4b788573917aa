//! The LBL role's parameters as a manifest writes them
//! (`[process.lbl.params]`, `variants.ekf`; every field defaulted but the
//! propeller's `k`, unknown keys refused) and their checks. Symbols are
//! paper 003 §V's and paper 004's: `k` (eqs. 1-2), `Q` (eq. 4), `q` and `γ`
//! (§V-C), `m_k` (§V-D). Where the papers give no number, the default is our
//! choice, tuned on the simulator's development seeds 7-9 only
//! (docs/design-notes.md, "LBL navigation").

use serde::Deserialize;

use crate::params::{OutOfRange, in_range, nonneg, positive};

/// Where the vehicle's velocity through the water comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum VelocitySource {
    /// Paper 004 eqs. 1-2: `k ω cos θ (cos ψ, sin ψ)` from the shaft speed
    /// (`sensor/propeller`) and the AHRS's pitch and heading, plus the
    /// current `(w_x, w_y)`.
    Propeller,
    /// A DVL's bottom-track velocity (`sensor/dvl`) rotated to north and
    /// east with the AHRS's attitude: a velocity over the ground, whose
    /// error (the heading's, mostly) the `w` states then take instead of the
    /// current (for vehicles and imported logs with a speed log instead of
    /// a propeller model).
    Dvl,
}

/// How the next transponder is chosen (paper 003 §V-D).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
pub enum Selection {
    /// The transponder that maximises the figure of merit `m_k`.
    #[serde(rename = "fom")]
    FigureOfMerit,
    /// Each transponder in turn, in the layout's order (LSTS DUNE's way).
    #[serde(rename = "round-robin")]
    RoundRobin,
}

/// The `ekf` variant's parameters (paper 003 §V).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LblParams {
    /// Where the velocity through the water comes from. Default
    /// `"propeller"` (Isurus).
    pub velocity_source: VelocitySource,
    /// `k`, the vehicle's advance per radian of propeller shaft rotation in
    /// steady state, m/rad (paper 004 eqs. 1-2). A property of the
    /// vehicle: required with `velocity_source = "propeller"`, no default.
    pub propeller_m_per_rad: Option<f64>,
    /// Estimate `k` as a fifth state (paper 003 §V: the filter "can even be
    /// used to estimate several parameters" of the velocity model). Default
    /// false.
    pub estimate_k: bool,
    /// σ of `k` at the start when it is estimated, as a fraction of
    /// `propeller_m_per_rad`. Default 0.05.
    pub k_sigma_rel: f64,
    /// `Q`'s `k` entry when it is estimated, (m/rad)²/s. Default 0 (a
    /// constant).
    pub q_k: f64,
    /// Rate of the filter's prediction steps and of `lbl/nav`, Hz (paper
    /// 003 §V-B: the vehicle's 10 Hz control loop). Default 10.
    pub rate_hz: f64,
    /// `Q`'s position entries (eq. 4), m²/s: the white part of the error of
    /// the dead-reckoned velocity (heading noise, shaft noise, turns the
    /// steady-state model does not describe). Default 0.001.
    pub q_position_m2_s: f64,
    /// `Q`'s current entries (eq. 4), (m/s)²/s: how fast `w_x`, `w_y`
    /// may wander (the current's own change, and the slowly varying heading
    /// bias that a 4-state model can only see as current). Default 1e-5.
    pub q_current_m2_s3: f64,
    /// `√q`: σ of a range measurement, m (§V-C). Default 0.32 (the
    /// simulator's 0.4 ms detection jitter is 0.30 m of range, the clock's
    /// 100 µs quantisation 0.02 m, the sound speed's error a few cm).
    pub range_sigma_m: f64,
    /// `γ`: a range is used when `‖r − r*‖²_{S⁻¹} ≤ γ` (§V-C). Default 9
    /// (3 σ).
    pub gate: f64,
    /// How the next transponder is chosen. Default `"fom"`.
    pub selection: Selection,
    /// The shortest time between two interrogations, s. Default 0: the next
    /// one leaves right after the previous reply (§V-D), at the next
    /// filter step.
    pub interval_s: f64,
    /// No reply for this long: interrogate the next one anyway, s (§V-D).
    /// Default 3 (a round trip of 2.2 km).
    pub timeout_s: f64,
    /// The ping and reply events are stamped on a clock of this resolution,
    /// each on the tick before it, so a round trip reads half a tick short
    /// on average; half of it is added back, s. Default 100e-6 (paper 003
    /// §IV's micro-controller).
    pub clock_resolution_s: f64,
    /// A round trip longer than a range of this is refused as absurd, m.
    /// Default 5000 (at most 9000).
    pub max_range_m: f64,
    /// Where the vehicle starts, north and east of the site's origin, m,
    /// when no GPS fix comes first. Default none: the first GPS fix at the
    /// surface starts the filter.
    pub initial_position_m: Option<[f64; 2]>,
    /// σ of `initial_position_m` per axis, m. Default 10.
    pub initial_sigma_m: f64,
    /// σ of the current at the start, m/s per axis. Default 0.3 (DESIGN
    /// §10: 0.1-0.3 m/s of current).
    pub initial_current_sigma_m_s: f64,
    /// A GPS fix is used only while the depth is shallower than this, m.
    /// Default 0.5.
    pub surface_depth_m: f64,
    /// The first GPS fix of a surfacing resets the position; later ones are
    /// weighed, and one whose 2-D innovation exceeds this χ² (2 degrees of
    /// freedom) resets it again. Default 13.8 (99.9 %).
    pub gps_gate: f64,
    /// Re-acquisition: after this many ranges refused in a row ...
    /// Default 2.
    pub reacquire_after: u32,
    /// ... with no range accepted for this long, s, the next range is
    /// accepted with the position's covariance widened to its innovation
    /// (the gate can never lock the filter out). Default 20.
    pub reacquire_s: f64,
    /// Re-acquisition, sooner: after this many ranges of one transponder
    /// refused in a row whose innovations agree (each within 4 σ of the
    /// range, `4 √q`, of the one before), the last of them is accepted as
    /// above. Ranges that keep telling the same story are the estimate's
    /// error, not the water's: a multipath reply is late by a random
    /// amount (the simulator's 0.75-15 m) and rare. Default 3.
    pub reacquire_agreeing: u32,
}

impl Default for LblParams {
    fn default() -> Self {
        Self {
            velocity_source: VelocitySource::Propeller,
            propeller_m_per_rad: None,
            estimate_k: false,
            k_sigma_rel: 0.05,
            q_k: 0.0,
            rate_hz: 10.0,
            q_position_m2_s: 0.001,
            q_current_m2_s3: 1e-5,
            range_sigma_m: 0.32,
            gate: 9.0,
            selection: Selection::FigureOfMerit,
            interval_s: 0.0,
            timeout_s: 3.0,
            clock_resolution_s: 100e-6,
            max_range_m: 5000.0,
            initial_position_m: None,
            initial_sigma_m: 10.0,
            initial_current_sigma_m_s: 0.3,
            surface_depth_m: 0.5,
            gps_gate: 13.8,
            reacquire_after: 2,
            reacquire_s: 20.0,
            reacquire_agreeing: 3,
        }
    }
}

/// The longest range accepted as `max_range_m`, m.
pub const MAX_RANGE_LIMIT_M: f64 = 9000.0;

impl LblParams {
    /// Checks every field; the error names the key and its range.
    pub fn validate(&self) -> anyhow::Result<()> {
        match (self.velocity_source, self.propeller_m_per_rad) {
            (VelocitySource::Propeller, None) => anyhow::bail!(
                "propeller_m_per_rad is required with velocity_source = \"propeller\": \
                 the vehicle's advance per radian of shaft rotation, k of paper 004 eqs. 1-2"
            ),
            (VelocitySource::Dvl, _) if self.estimate_k => anyhow::bail!(
                "estimate_k needs velocity_source = \"propeller\" (k is the propeller's)"
            ),
            _ => {}
        }
        if !(2..=1000).contains(&self.reacquire_agreeing) {
            anyhow::bail!(
                "reacquire_agreeing = {} is outside [2, 1000]",
                self.reacquire_agreeing
            );
        }
        if self.reacquire_after == 0 {
            anyhow::bail!("reacquire_after = 0 is outside [1, 1000]");
        }
        if self.reacquire_after > 1000 {
            anyhow::bail!(
                "reacquire_after = {} is outside [1, 1000]",
                self.reacquire_after
            );
        }
        let r = (|| -> Result<(), OutOfRange> {
            if let Some(k) = self.propeller_m_per_rad {
                in_range("propeller_m_per_rad", k, 0.0, 10.0, true, "(0, 10]")?;
            }
            in_range("k_sigma_rel", self.k_sigma_rel, 0.0, 1.0, true, "(0, 1]")?;
            nonneg("q_k", self.q_k)?;
            in_range("rate_hz", self.rate_hz, 0.1, 1000.0, false, "[0.1, 1000]")?;
            nonneg("q_position_m2_s", self.q_position_m2_s)?;
            nonneg("q_current_m2_s3", self.q_current_m2_s3)?;
            in_range(
                "range_sigma_m",
                self.range_sigma_m,
                0.0,
                1000.0,
                true,
                "(0, 1000]",
            )?;
            in_range("gate", self.gate, 1.0, 1e6, false, "[1, 1e6]")?;
            in_range(
                "interval_s",
                self.interval_s,
                0.0,
                3600.0,
                false,
                "[0, 3600]",
            )?;
            in_range("timeout_s", self.timeout_s, 0.0, 3600.0, true, "(0, 3600]")?;
            in_range(
                "clock_resolution_s",
                self.clock_resolution_s,
                0.0,
                1.0,
                false,
                "[0, 1]",
            )?;
            in_range(
                "max_range_m",
                self.max_range_m,
                1.0,
                MAX_RANGE_LIMIT_M,
                false,
                "[1, 9000]",
            )?;
            if let Some([n, e]) = self.initial_position_m {
                in_range("initial_position_m", n, -1e6, 1e6, false, "±1e6")?;
                in_range("initial_position_m", e, -1e6, 1e6, false, "±1e6")?;
            }
            positive("initial_sigma_m", self.initial_sigma_m)?;
            in_range(
                "initial_current_sigma_m_s",
                self.initial_current_sigma_m_s,
                0.0,
                10.0,
                true,
                "(0, 10]",
            )?;
            in_range(
                "surface_depth_m",
                self.surface_depth_m,
                0.0,
                100.0,
                false,
                "[0, 100]",
            )?;
            in_range("gps_gate", self.gps_gate, 1.0, 1e6, false, "[1, 1e6]")?;
            positive("reacquire_s", self.reacquire_s)?;
            Ok(())
        })();
        r.map_err(|e| anyhow::anyhow!("{} = {} is outside {}", e.name, e.value, e.range))
    }

    /// The step period, ns.
    pub fn period_ns(&self) -> u64 {
        ((1e9 / self.rate_hz).round() as u64).max(1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn with_k() -> LblParams {
        LblParams {
            propeller_m_per_rad: Some(0.0105),
            ..Default::default()
        }
    }

    #[test]
    fn defaults_need_only_k() {
        let e = LblParams::default().validate().expect_err("no k");
        assert!(e.to_string().contains("propeller_m_per_rad"), "{e}");
        with_k().validate().expect("valid");
        LblParams {
            velocity_source: VelocitySource::Dvl,
            ..Default::default()
        }
        .validate()
        .expect("a DVL needs no k");
    }

    #[test]
    fn bad_values_are_named() {
        let mut p = with_k();
        p.gate = f64::NAN;
        assert!(p.validate().expect_err("NaN").to_string().contains("gate"));
        let mut p = with_k();
        p.timeout_s = 0.0;
        assert!(p.validate().is_err());
        let mut p = with_k();
        p.max_range_m = 1e5;
        assert!(
            p.validate()
                .expect_err("range")
                .to_string()
                .contains("max_range_m")
        );
        let mut p = with_k();
        p.reacquire_after = 0;
        assert!(p.validate().is_err());
    }

    #[test]
    fn the_manifest_spells_the_choices() {
        let p: LblParams = toml::from_str(
            "propeller_m_per_rad = 0.01\nselection = \"round-robin\"\nvelocity_source = \"dvl\"",
        )
        .expect("toml");
        assert_eq!(p.selection, Selection::RoundRobin);
        assert_eq!(p.velocity_source, VelocitySource::Dvl);
        assert!(toml::from_str::<LblParams>("selection = \"best\"").is_err());
        assert!(toml::from_str::<LblParams>("gamma = 9").is_err());
    }
}
