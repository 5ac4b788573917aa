//! The LBL filter a recording ran: its recorded manifest (the `manifest`
//! entry of `nauta.run`, with the run's overrides applied), or another one
//! given on the command line, with `--set` overrides; the `nauta-lbl`
//! process's variant and parameters, and `[site]`'s origin, declination,
//! sound speed and transponders ([`Manifest::lbl_core`]).

use std::path::Path;

use anyhow::Context as _;
use nauta_estimation::lbl::Lbl;
use nauta_log::reader::Recording;
use nauta_runtime::Manifest;

/// The binary of the LBL role.
pub const LBL_BIN: &str = "nauta-lbl";

/// Where the manifest comes from.
#[derive(Debug, Clone, Copy)]
pub enum ManifestSource<'a> {
    /// The one recorded in the input (`nauta.run`'s `manifest`).
    Recorded,
    /// A file.
    File(&'a Path),
}

/// The manifest of `source` (for the recorded one, `input` names the file
/// in errors) with `overrides` (`KEY=VALUE`, as `nauta launch --set`).
pub fn manifest(
    source: ManifestSource<'_>,
    recording: &Recording,
    input: &Path,
    overrides: &[String],
) -> anyhow::Result<Manifest> {
    match source {
        ManifestSource::File(path) => Manifest::load_with(path, overrides),
        ManifestSource::Recorded => {
            let text = recording
                .metadata(nauta_log::META_RUN)
                .and_then(|m| m.get("manifest"))
                .with_context(|| {
                    format!(
                        "{} holds no manifest (metadata {}): give the one it was made with, --manifest FILE",
                        input.display(),
                        nauta_log::META_RUN
                    )
                })?;
            let name = format!("the manifest recorded in {}", input.display());
            let mut table: toml::Table =
                toml::from_str(text).with_context(|| format!("cannot parse {name}"))?;
            for o in overrides {
                nauta_runtime::manifest::apply_override(&mut table, o)
                    .with_context(|| format!("{name}: in --set {o}"))?;
            }
            Manifest::parse(Path::new(&name), &toml::to_string(&table)?)
        }
    }
}

/// The process of `manifest` that runs the LBL role: `process` if given,
/// else the only one whose binary is `nauta-lbl`.
pub fn lbl_process(manifest: &Manifest, process: Option<&str>) -> anyhow::Result<String> {
    let file = manifest.path.display();
    if let Some(name) = process {
        manifest.process(name)?;
        return Ok(name.to_owned());
    }
    let is_lbl = |bin: &str| Path::new(bin).file_name() == Some(std::ffi::OsStr::new(LBL_BIN));
    let found: Vec<&String> = manifest
        .processes
        .iter()
        .filter(|(_, p)| is_lbl(&p.bin))
        .map(|(name, _)| name)
        .collect();
    match found.as_slice() {
        [one] => Ok((*one).clone()),
        [] => anyhow::bail!(
            "{file} runs no {LBL_BIN} process: nothing to smooth (give one with --manifest FILE)"
        ),
        several => anyhow::bail!(
            "{file} runs {} {LBL_BIN} processes ({}): choose one with --process NAME",
            several.len(),
            several
                .iter()
                .map(|s| s.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// The LBL filter of `process` in `manifest`, not yet fed: its variant (the
/// default when it names none) and [`Manifest::lbl_core`], as `nauta-lbl`
/// builds it.
pub fn lbl_filter(manifest: &Manifest, process: &str) -> anyhow::Result<Lbl> {
    let file = manifest.path.display();
    let section = manifest.process(process)?;
    let variant = section
        .variant
        .as_deref()
        .unwrap_or(nauta_estimation::lbl::VARIANTS[0]);
    anyhow::ensure!(
        nauta_estimation::lbl::VARIANTS.contains(&variant),
        "{file}: process.{process}: unknown variant {variant:?}; {LBL_BIN}'s are {:?}",
        nauta_estimation::lbl::VARIANTS
    );
    manifest.lbl_core(process, variant)
}
