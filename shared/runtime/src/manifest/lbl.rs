//! The LBL role's core from a manifest: the process's variant parameters
//! and `[site]`'s origin, declination, sound speed and transponders. The
//! one place that builds it, for `nauta-lbl` and for `nauta smooth` (which
//! runs a recording's filter again from its recorded manifest).

use anyhow::Context as _;
use nauta_estimation::lbl::{Lbl, LblParams, LblSite};

use super::Manifest;

impl Manifest {
    /// The LBL filter of `process` with `variant`'s parameters on the
    /// manifest's site, not yet fed. Every error names the file and the key.
    pub fn lbl_core(&self, process: &str, variant: &str) -> anyhow::Result<Lbl> {
        let file = self.path.display();
        let params: LblParams = self.params(process, Some(variant))?;
        let site = self.site.as_ref().with_context(|| {
            format!("{file}: the manifest has no [site]: LBL needs the origin, the transponders and the sound speed")
        })?;
        let layout = site.layout().with_context(|| {
            format!(
                "{file}: [site] has no transponders (site.transponders, or a process's lbl_layout)"
            )
        })?;
        let sound_speed_m_s = site.sound_speed_m_s.with_context(|| {
            format!(
                "{file}: [site] has no sound_speed_m_s (the sound speed the vehicle assumes, m/s)"
            )
        })?;
        let lbl_site = LblSite {
            origin_lat_rad: site.latitude_deg.to_radians(),
            origin_lon_rad: site.longitude_deg.to_radians(),
            declination_rad: site.magnetic_declination_deg.to_radians(),
            sound_speed_m_s,
            layout,
        };
        Lbl::new(&params, lbl_site).with_context(|| format!("{file}: process.{process}"))
    }
}
