//! `nauta eval` over a running pipeline instead of a recording: the launcher
//! feeds [`Data::take`] the truth and estimate messages its taps receive (the
//! bytes a logger would record), and evaluates them with [`super::evaluate`]
//! at the end of the run. This file adds only what a recording provides and a
//! tap does not: the run's metadata and the order by stamp.

use nauta_log::run::RunInfo;
use nauta_runtime::Manifest;

use super::Data;

/// What the `nauta.run` record of a recording of this run would say about
/// its frame: read from the effective manifest, under the key the logger
/// writes it to.
pub fn run_info(manifest: &Manifest) -> RunInfo {
    match manifest.to_toml() {
        Ok(text) => RunInfo::of_manifest(&text, Some(crate::presets::simulated)),
        Err(e) => {
            tracing::warn!(error = %format!("{e:#}"), "the manifest gives no local frame");
            RunInfo::default()
        }
    }
}
/// Orders every stream of `data` by stamp, one truth sample per stamp, as
/// [`Data::read`] leaves a recording (taps receive each publisher's messages
/// in its order, a restarted or swapped-in instance's after the last one's).
pub fn sort(data: &mut Data) {
    data.truth.sort_by_key(|t| t.stamp_ns);
    data.truth.dedup_by_key(|t| t.stamp_ns);
    data.gps.sort_by_key(|g| g.stamp_ns);
    for s in data.streams.values_mut() {
        s.samples.sort_by_key(|e| e.stamp_ns);
    }
}
