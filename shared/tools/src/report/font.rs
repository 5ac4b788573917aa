//! The font of the plots' text. plotters draws text with `ab_glyph` from a
//! font file registered at run time (no C font stack to build against): the
//! file named by `NAUTA_FONT`, else a DejaVu or Liberation sans found in the
//! usual places, else what fontconfig's `fc-match sans-serif` names.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use anyhow::Context as _;

/// The family name the plots use.
pub const FAMILY: &str = "sans-serif";

/// Environment variable naming a TrueType/OpenType font file.
pub const FONT_ENV: &str = "NAUTA_FONT";

const CANDIDATES: &[&str] = &[
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu-sans-fonts/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
    "/usr/share/fonts/liberation-sans/LiberationSans-Regular.ttf",
    "/usr/local/share/fonts/DejaVuSans.ttf",
];

/// Finds a font file.
fn find() -> anyhow::Result<PathBuf> {
    if let Some(p) = std::env::var_os(FONT_ENV) {
        let p = PathBuf::from(p);
        anyhow::ensure!(p.is_file(), "{FONT_ENV}={} is not a font file", p.display());
        return Ok(p);
    }
    if let Some(p) = CANDIDATES.iter().map(Path::new).find(|p| p.is_file()) {
        return Ok(p.to_owned());
    }
    let fc = std::process::Command::new("fc-match")
        .args(["-f", "%{file}", "sans-serif"])
        .stderr(std::process::Stdio::null())
        .output();
    if let Ok(out) = fc
        && out.status.success()
    {
        let p = PathBuf::from(String::from_utf8_lossy(&out.stdout).trim());
        if p.is_file() {
            return Ok(p);
        }
    }
    anyhow::bail!(
        "no font for the plots' text: set {FONT_ENV}=/path/to/font.ttf, or install a sans font (Debian: fonts-dejavu-core); looked in {} and asked fc-match",
        CANDIDATES.join(", ")
    )
}

/// Registers the font once per process; returns its file.
pub fn register() -> anyhow::Result<&'static Path> {
    static FONT: OnceLock<PathBuf> = OnceLock::new();
    if let Some(p) = FONT.get() {
        return Ok(p);
    }
    let path = find()?;
    let bytes =
        std::fs::read(&path).with_context(|| format!("cannot read the font {}", path.display()))?;
    // plotters keeps registered fonts for the life of the process.
    let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
    plotters::style::register_font(FAMILY, plotters::style::FontStyle::Normal, bytes)
        .map_err(|_| anyhow::anyhow!("{} is not a font plotters can read", path.display()))?;
    Ok(FONT.get_or_init(|| path))
}
