//! The LBL filter's input handlers: the AHRS, depth, DVL and propeller held
//! for the next 10 Hz step; GPS fixes and transponder replies checked, matched
//! to their interrogation and queued for the step that applies them (paper
//! 003 §V-B, §V-C).

use super::*;

impl Lbl {
    pub(super) fn on_ahrs(&mut self, a: &Ahrs) {
        let heading = a.heading_mag_rad + self.site.declination_rad;
        self.st.held.attitude = Some(([a.roll_rad, a.pitch_rad, heading], a.stamp_ns));
    }

    pub(super) fn on_depth(&mut self, d: &Depth) {
        self.st.held.depth = Some((d.depth_m, d.stamp_ns));
        if d.depth_m > self.params.surface_depth_m {
            self.st.submerged = true;
        }
    }

    pub(super) fn on_dvl(&mut self, d: &Dvl) {
        if self.params.velocity_source != VelocitySource::Dvl
            || !d.bottom_lock
            || d.beams_valid == 0
        {
            return;
        }
        let Some((att, _)) = self.st.held.attitude else {
            return;
        };
        let v = from_euler(att[0], att[1], att[2]) * d.velocity_body_m_s.as_nalgebra();
        self.st.held.ground_velocity = Some(([v.x, v.y], d.stamp_ns));
    }

    pub(super) fn on_gps(&mut self, g: &Gps) -> Result<(), EstimatorError> {
        if g.quality == 0 {
            self.st.stats.gps_refused += 1;
            return Err(refuse("gps_no_fix", "a GPS message without a fix"));
        }
        if let Some((d, _)) = self.st.held.depth
            && d > self.params.surface_depth_m
        {
            self.st.stats.gps_refused += 1;
            return Err(refuse(
                "gps_submerged",
                format!(
                    "a GPS fix at {d:.2} m of depth (fixes are used above {} m)",
                    self.params.surface_depth_m
                ),
            ));
        }
        let (n, e) = crate::local::north_east_of(
            self.site.origin_lat_rad,
            self.site.origin_lon_rad,
            g.lat_rad,
            g.lon_rad,
        );
        if !(n.abs() <= 1e6 && e.abs() <= 1e6) {
            self.st.stats.gps_refused += 1;
            return Err(refuse(
                "gps_far",
                "a GPS fix more than 1000 km from the site's origin",
            ));
        }
        let reset = self.filter.is_none()
            || self.st.submerged
            || self.st.pending_gps.is_some_and(|p| p.reset);
        self.st.pending_gps = Some(PendingGps {
            stamp_ns: g.stamp_ns,
            position_m: [n, e],
            var_m2: g.horizontal_std_m.max(MIN_GPS_STD_M).powi(2),
            reset,
        });
        Ok(())
    }

    pub(super) fn on_reply(&mut self, r: &LblReplyReading) -> Result<(), EstimatorError> {
        let id = r.transponder_id;
        let Some(tx) = self.site.layout.get(id).copied() else {
            self.st.stats.unknown_transponder += 1;
            return Err(refuse(
                "unknown_transponder",
                format!("a reply from transponder {id}, which the site does not have"),
            ));
        };
        let elapsed_s = r.stamp_ns.saturating_sub(r.interrogation_stamp_ns) as f64 * 1e-9;
        let range_m = range_of_round_trip(
            r.round_trip_s,
            tx.turnaround_s,
            self.site.sound_speed_m_s,
            0.5 * self.params.clock_resolution_s,
        );
        if !(range_m > 0.0
            && range_m <= self.params.max_range_m
            && r.round_trip_s <= elapsed_s + ROUND_TRIP_SLACK_S)
        {
            self.st.stats.bad_round_trip += 1;
            return Err(refuse(
                "round_trip",
                format!(
                    "a round trip of {} s to transponder {id} ({:.1} s after the ping) gives \
                     a range of {range_m:.1} m, not in (0, {}]",
                    r.round_trip_s, elapsed_s, self.params.max_range_m
                ),
            ));
        }
        // Checked before matching, so that a garbled reading does not use
        // up its interrogation.
        self.match_ping(r)?;
        self.st.stats.replies += 1;
        let mid_ns =
            r.interrogation_stamp_ns + (r.stamp_ns - r.interrogation_stamp_ns.min(r.stamp_ns)) / 2;
        let t_state = self
            .st
            .next_step_ns
            .map_or(0, |n| n.saturating_sub(self.period_ns));
        let a_now = self.held_basis();
        let gated = match &self.filter {
            Some(Filter::Four(k)) => self.gate(k, t_state, mid_ns, id, range_m, a_now),
            Some(Filter::Five(k)) => self.gate(k, t_state, mid_ns, id, range_m, a_now),
            None => None,
        };
        let Some((nu, d2)) = gated else {
            self.st.stats.no_position += 1;
            return Err(refuse(
                "no_position",
                "a reply before the filter has a position and a depth",
            ));
        };
        let accepted = d2 <= self.params.gate;
        let stale = self
            .st
            .last_accept_ns
            .is_some_and(|l| r.stamp_ns.saturating_sub(l) as f64 * 1e-9 >= self.params.reacquire_s);
        let agreeing = if accepted {
            0
        } else {
            self.st
                .note_refusal(id, nu, 4.0 * self.params.range_sigma_m)
        };
        let reacquire = !accepted
            && ((self.st.refused_in_row >= self.params.reacquire_after && stale)
                || agreeing >= self.params.reacquire_agreeing);
        let after_gap = stale;
        self.st.last = LastRange {
            innovation_m: nu,
            transponder_id: id,
            accepted: accepted || reacquire,
        };
        if !(accepted || reacquire) {
            self.st.refused_in_row += 1;
            self.st.stats.gated += 1;
            return Err(refuse(
                "gated",
                format!(
                    "a range to transponder {id} {nu:+.2} m from the estimate: ‖r − r*‖²/S = {d2:.1} > γ = {}",
                    self.params.gate
                ),
            ));
        }
        if reacquire {
            self.st.stats.reacquisitions += 1;
            tracing::info!(
                transponder = id,
                innovation_m = nu,
                agreeing,
                "re-acquiring: no range accepted for {:.0} s",
                self.st
                    .last_accept_ns
                    .map_or(0.0, |l| r.stamp_ns.saturating_sub(l) as f64 * 1e-9)
            );
        }
        self.st.clear_refusals(id);
        self.st.refused_in_row = 0;
        self.st.last_accept_ns = Some(r.stamp_ns);
        if self.st.pending.len() < MAX_PENDING {
            self.st.pending.push(PendingRange {
                stamp_ns: r.stamp_ns,
                transponder_id: id,
                range_m,
                mid_ns,
                reacquire,
                after_gap,
            });
        }
        Ok(())
    }

    /// The reply's interrogation: one of ours not yet answered (or, when
    /// replaying, a pair of transponder and stamp not seen yet).
    pub(super) fn match_ping(&mut self, r: &LblReplyReading) -> Result<(), EstimatorError> {
        let id = r.transponder_id;
        let slack_ns = ((2.0 * self.params.clock_resolution_s).max(1e-3) * 1e9) as u64;
        let now = r.stamp_ns;
        if self.replay {
            let recent = &mut self.st.pings.recent;
            match recent
                .iter_mut()
                .find(|p| p.transponder_id == id && p.stamp_ns == r.interrogation_stamp_ns)
            {
                Some(p) if p.answered => {
                    self.st.stats.duplicate_replies += 1;
                    return Err(refuse(
                        "duplicate_reply",
                        "a second reply to one interrogation",
                    ));
                }
                // The filter's own ping of that instant (the same schedule).
                Some(p) => p.answered = true,
                None => {
                    recent.push(SentPing {
                        transponder_id: id,
                        stamp_ns: r.interrogation_stamp_ns,
                        answered: true,
                    });
                    self.forget_old_pings(now);
                }
            }
            return Ok(());
        }
        let pings = &mut self.st.pings;
        let Some(p) = pings.recent.iter_mut().find(|p| {
            p.transponder_id == id
                && r.interrogation_stamp_ns >= p.stamp_ns
                && r.interrogation_stamp_ns - p.stamp_ns <= slack_ns
        }) else {
            self.st.stats.no_interrogation += 1;
            return Err(refuse(
                "no_interrogation",
                format!(
                    "a reply from transponder {id} to an interrogation at {} ns that we did not send",
                    r.interrogation_stamp_ns
                ),
            ));
        };
        if p.answered {
            self.st.stats.duplicate_replies += 1;
            return Err(refuse(
                "duplicate_reply",
                format!("a second reply from transponder {id} to one interrogation"),
            ));
        }
        p.answered = true;
        let p = *p;
        if pings
            .outstanding
            .is_some_and(|o| o.transponder_id == p.transponder_id && o.stamp_ns == p.stamp_ns)
        {
            pings.outstanding = None;
        }
        Ok(())
    }

    /// `ν = r − r*` and `ν²/S` at the state of `t_state` (paper 003 §V-C).
    pub(super) fn gate<const N: usize>(
        &self,
        k: &Kf<N>,
        t_state: u64,
        mid_ns: u64,
        id: u32,
        range_m: f64,
        a_now: Basis,
    ) -> Option<(f64, f64)> {
        let (r_star, h) = self.range_model(&k.x, t_state, mid_ns, id, a_now)?;
        let nu = range_m - r_star;
        let s = k.innovation_variance(&h, self.params.range_sigma_m.powi(2));
        Some((nu, nu * nu / s))
    }

    pub(super) fn on_propeller(&mut self, p: &Propeller) {
        self.st.held.shaft = Some((p.shaft_speed_rad_s, p.stamp_ns));
    }
}
