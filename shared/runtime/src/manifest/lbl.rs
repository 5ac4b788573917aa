//! The LBL role's core from a manifest: the process's variant parameters
//! and `[site]`'s origin, declination, sound speed and transponders
//! ([`super::Site::lbl_site`]), for `nauta smooth` (which runs a
//! recording's filter again from its recorded manifest) and the benches.

use anyhow::Context as _;
use nauta_estimation::lbl::{Lbl, LblParams};

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
        let lbl_site = site
            .lbl_site()
            .map_err(|e| anyhow::anyhow!("{file}: {e}"))?;
        Lbl::new(&params, lbl_site).with_context(|| format!("{file}: process.{process}"))
    }
}
