//! Manifests (DESIGN §5): the TOML file that describes a run and its processes.
//! Unknown keys are refused; errors name the file, the line and the key.
//! The launcher applies `--set` overrides and passes the effective manifest to
//! every process, which reads its own parameters from it.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{Context as _, bail};
use serde::Deserialize;
use serde::de::DeserializeOwned;

use crate::clock::ClockMode;
pub use crate::manifest_limits::{
    LAUNCHER_FLAGS, MAX_BACKOFF_MS, MAX_DEADLINE_MS, MAX_DURATION_S, MAX_MANIFEST_BYTES,
    MAX_PROCESS_NAME, MAX_RATE, MAX_WINDOW_S, MIN_RATE,
};
use crate::manifest_limits::{check_process_name, launcher_flag, read_manifest};

mod lbl;
mod site;
use site::RawSite;
pub use site::{DeclinationSource, SOUND_SPEED_RANGE_M_S, Site, TranspondersSource};

/// `[run]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunSection {
    /// `"auto"` (unique per run) or a fixed namespace.
    #[serde(default = "auto")]
    pub namespace: String,
    /// `"sim"` or `"wall"`.
    #[serde(default = "sim")]
    pub clock: String,
    /// Mission duration, s of simulated time.
    pub duration_s: f64,
    /// Seed of every random generator of the run.
    #[serde(default)]
    pub seed: u64,
    /// Multiple of real time in `wall` mode.
    #[serde(default = "one")]
    pub rate: f64,
    /// How long a `sim`-mode publisher waits on a full subscriber before giving up, ms.
    #[serde(default = "deadline_ms")]
    pub backpressure_deadline_ms: u64,
    /// Set by the launcher in the effective manifest it hands to processes: the
    /// file the user gave, so that errors name it.
    #[serde(default)]
    pub source: Option<String>,
}

fn auto() -> String {
    "auto".into()
}
fn sim() -> String {
    "sim".into()
}
fn one() -> f64 {
    1.0
}
fn deadline_ms() -> u64 {
    2000
}

/// `[process.NAME.restart]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RestartSection {
    /// `never`, `on-failure` or `always`.
    pub policy: String,
    /// Most restarts within `window_s`.
    #[serde(default)]
    pub max: Option<u32>,
    /// Window for `max`, s.
    #[serde(default)]
    pub window_s: Option<f64>,
    /// Backoff from the first to the longest delay, ms.
    #[serde(default)]
    pub backoff_ms: Option<[u64; 2]>,
}

/// When a process that exited is started again.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RestartPolicy {
    /// Never (the default).
    Never,
    /// After a non-zero exit or a death by signal.
    OnFailure,
    /// After any exit, including 0, until the run ends.
    Always,
}

impl RestartPolicy {
    /// Parses `never`, `on-failure` or `always`.
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "never" => Some(Self::Never),
            "on-failure" => Some(Self::OnFailure),
            "always" => Some(Self::Always),
            _ => None,
        }
    }
}

/// `[process.NAME]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProcessSection {
    /// Binary name (`nauta-sensor`), found next to `nauta`, then on PATH; a
    /// path (with a `/`) is used as given. Not empty, not a directory.
    pub bin: String,
    /// Extra command-line arguments.
    #[serde(default)]
    pub args: Vec<String>,
    /// The variant to run (for estimators with several implementations).
    #[serde(default)]
    pub variant: Option<String>,
    /// Parameters per variant.
    #[serde(default)]
    pub variants: BTreeMap<String, toml::Table>,
    /// Parameters common to every variant.
    #[serde(default)]
    pub params: toml::Table,
    /// Restart policy.
    #[serde(default)]
    pub restart: Option<RestartSection>,
    /// Processes that must be ready before this one starts.
    #[serde(default)]
    pub after: Vec<String>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawManifest {
    run: RunSection,
    #[serde(default)]
    site: Option<RawSite>,
    #[serde(default)]
    process: BTreeMap<String, ProcessSection>,
}

/// A parsed and checked manifest.
#[derive(Debug, Clone)]
pub struct Manifest {
    /// Where it was read from.
    pub path: PathBuf,
    /// `[run]`.
    pub run: RunSection,
    /// `[site]`, if given.
    pub site: Option<Site>,
    /// `[process.*]`, by name.
    pub processes: BTreeMap<String, ProcessSection>,
    table: toml::Table,
    text: String,
    /// The `--set` overrides applied, as given (`KEY=VALUE`), for errors.
    overrides: Vec<String>,
}

impl Manifest {
    /// Reads and checks `path`.
    pub fn load(path: &Path) -> anyhow::Result<Self> {
        Self::load_with(path, &[])
    }

    /// Reads `path`, applies `--set KEY=VALUE` overrides, and checks the result.
    pub fn load_with(path: &Path, overrides: &[String]) -> anyhow::Result<Self> {
        let text = read_manifest(path)?;
        let mut table: toml::Table = toml::from_str(&text)
            .map_err(|e| anyhow::anyhow!("{}: {}", path.display(), e.to_string().trim_end()))?;
        for o in overrides {
            apply_override(&mut table, o)
                .with_context(|| format!("{}: in --set {o}", path.display()))?;
        }
        Self::from_table(path, table, text, overrides).map_err(|e| Self::locate(path, overrides, e))
    }

    /// A schema error of the manifest with overrides has no line (it comes
    /// from the merged table, not the text): if the file alone has it, the
    /// file's error (with line and key) is the one to report; otherwise it is
    /// the first override that brings it, named.
    fn locate(path: &Path, overrides: &[String], e: anyhow::Error) -> anyhow::Error {
        let msg = e.to_string();
        let Some(bare) = msg.strip_prefix(&format!("{}: ", path.display())) else {
            return e;
        };
        if overrides.is_empty()
            || bare.contains("--set")
            || bare.starts_with(|c: char| c.is_ascii_digit())
        {
            return e;
        }
        let schema_of = |overrides: &[String]| -> Option<String> {
            let text = read_manifest(path).ok()?;
            let mut table: toml::Table = toml::from_str(&text).ok()?;
            for o in overrides {
                apply_override(&mut table, o).ok()?;
            }
            let same = toml::from_str::<toml::Table>(&text).ok()? == table;
            let raw = if same {
                toml::from_str::<RawManifest>(&text).map(|_| ())
            } else {
                toml::Table::try_into::<RawManifest>(table).map(|_| ())
            };
            raw.err().map(|e| e.to_string().trim_end().to_owned())
        };
        // The file alone.
        if let Some(file_error) = schema_of(&[])
            && file_error.contains(bare.lines().next().unwrap_or(bare))
        {
            return anyhow::anyhow!("{}: {file_error}", path.display());
        }
        // The first override that makes the schema fail.
        for i in 0..overrides.len() {
            if schema_of(&overrides[..=i]).is_some() {
                return anyhow::anyhow!(
                    "{}: on the command line ({}): {bare}",
                    path.display(),
                    overrides[i]
                );
            }
        }
        e
    }

    /// Parses manifest text (for tests and generated manifests).
    pub fn parse(path: &Path, text: &str) -> anyhow::Result<Self> {
        let table: toml::Table = toml::from_str(text)
            .map_err(|e| anyhow::anyhow!("{}: {}", path.display(), e.to_string().trim_end()))?;
        Self::from_table(path, table, text.to_owned(), &[])
    }

    fn from_table(
        path: &Path,
        table: toml::Table,
        text: String,
        overrides: &[String],
    ) -> anyhow::Result<Self> {
        // Deserialize from the text when unchanged so errors carry line numbers.
        let raw: RawManifest = match toml::from_str::<toml::Table>(&text) {
            Ok(orig) if orig == table => toml::from_str(&text),
            _ => toml::Table::try_into(table.clone()),
        }
        .map_err(|e| anyhow::anyhow!("{}: {}", path.display(), e.to_string().trim_end()))?;
        // An effective manifest (written by the launcher) names the user's
        // file: errors give that file's lines, not the copy's (none if the
        // file cannot be read any more).
        let (path, text) = match &raw.run.source {
            Some(src) => {
                let src = PathBuf::from(src);
                let original = read_manifest(&src).unwrap_or_default();
                (src, original)
            }
            None => (path.to_owned(), text),
        };
        let mut m = Manifest {
            path,
            run: raw.run,
            site: None,
            processes: raw.process,
            table,
            text,
            overrides: overrides.to_vec(),
        };
        if let Some(site) = raw.site {
            // The place first: the model is asked only about a real one.
            let mut site = if !(site.latitude_deg.abs() <= 90.0
                && site.longitude_deg.abs() <= 180.0)
            {
                RawSite {
                    magnetic_declination_deg: Some(site.magnetic_declination_deg.unwrap_or(0.0)),
                    ..site
                }
                .resolve()
                .map_err(|(key, e)| m.err(key, e))?
            } else {
                site.resolve().map_err(|(key, e)| m.err(key, e))?
            };
            site.resolve_acoustics(m.named_layout())
                .map_err(|(key, e)| m.err(&key, e))?;
            m.site = Some(site);
        }
        m.check()?;
        Ok(m)
    }

    /// The first process (by name) whose parameters name a transponder
    /// layout (`params.lbl_layout`, or its variant's), with that name.
    fn named_layout(&self) -> Option<(String, String)> {
        self.processes.iter().find_map(|(name, p)| {
            let in_variant = p
                .variant
                .as_ref()
                .and_then(|v| p.variants.get(v))
                .and_then(|t| t.get("lbl_layout"));
            in_variant
                .or_else(|| p.params.get("lbl_layout"))
                .and_then(toml::Value::as_str)
                .map(|layout| (name.clone(), layout.to_owned()))
        })
    }

    /// An error about `key` (dotted, e.g. `process.attitude.bin`), naming the
    /// file and, when the key is written in it, the line.
    pub fn error_at(&self, key: &str, msg: impl std::fmt::Display) -> anyhow::Error {
        self.err(key, msg)
    }

    /// Process names in start order: every process after those in its
    /// `after` list, otherwise in the order `first` ranks them (lower first),
    /// then by name. `check` has refused cycles.
    pub fn start_order(&self, first: impl Fn(&str) -> u8) -> Vec<String> {
        let mut done: Vec<String> = Vec::new();
        let mut left: Vec<&String> = self.processes.keys().collect();
        left.sort_by_key(|n| first(n));
        while !left.is_empty() {
            let Some(i) = left.iter().position(|n| {
                self.processes[*n]
                    .after
                    .iter()
                    .all(|a| done.iter().any(|d| d == a))
            }) else {
                // A cycle (refused by `check`): keep the rest in rank order.
                done.extend(left.drain(..).cloned());
                break;
            };
            done.push(left.remove(i).clone());
        }
        done
    }

    fn err(&self, key: &str, msg: impl std::fmt::Display) -> anyhow::Error {
        // A value an override set is the override's, not the file's line's.
        if let Some(o) = self.overrides.iter().rev().find(|o| {
            let k = override_key(o);
            key == k || key.starts_with(&format!("{k}."))
        }) {
            let k = o.split_once('=').map_or(o.as_str(), |(k, _)| k);
            return anyhow::anyhow!(
                "{}: {key} (set on the command line: {k}): {msg}",
                self.path.display()
            );
        }
        match line_of(&self.text, key) {
            Some(line) => anyhow::anyhow!("{}:{line}: {key}: {msg}", self.path.display()),
            None => anyhow::anyhow!("{}: {key}: {msg}", self.path.display()),
        }
    }

    fn check(&self) -> anyhow::Result<()> {
        let r = &self.run;
        if !(r.duration_s > 0.0 && r.duration_s <= MAX_DURATION_S) {
            return Err(self.err(
                "run.duration_s",
                format!(
                    "must be a positive number of seconds, at most {MAX_DURATION_S}, got {:?}",
                    r.duration_s
                ),
            ));
        }
        if !(r.rate >= MIN_RATE && r.rate <= MAX_RATE) {
            return Err(self.err(
                "run.rate",
                format!(
                    "must be a positive number in [{MIN_RATE}, {MAX_RATE}], got {:?}",
                    r.rate
                ),
            ));
        }
        if !(r.backpressure_deadline_ms > 0 && r.backpressure_deadline_ms <= MAX_DEADLINE_MS) {
            return Err(self.err(
                "run.backpressure_deadline_ms",
                format!(
                    "must be in [1, {MAX_DEADLINE_MS}] ms, got {}",
                    r.backpressure_deadline_ms
                ),
            ));
        }
        ClockMode::parse(&r.clock, r.rate).map_err(|e| self.err("run.clock", e))?;
        if r.namespace != "auto" {
            crate::Namespace::new(&r.namespace).map_err(|e| self.err("run.namespace", e))?;
        }
        if let Some(s) = &self.site {
            if !(s.latitude_deg.abs() <= 90.0) {
                return Err(self.err(
                    "site.latitude_deg",
                    format!("must be within ±90, got {}", s.latitude_deg),
                ));
            }
            if !(s.longitude_deg.abs() <= 180.0) {
                return Err(self.err(
                    "site.longitude_deg",
                    format!("must be within ±180, got {}", s.longitude_deg),
                ));
            }
            if !(s.magnetic_declination_deg.abs() <= 180.0) {
                return Err(self.err(
                    "site.magnetic_declination_deg",
                    format!("must be within ±180, got {}", s.magnetic_declination_deg),
                ));
            }
        }
        if self.processes.is_empty() {
            return Err(anyhow::anyhow!(
                "{}: no process: a manifest runs at least one [process.NAME] with a bin",
                self.path.display()
            ));
        }
        for (name, p) in &self.processes {
            check_process_name(name).map_err(|e| self.err(&format!("process.{name}"), e))?;
            if let Some(flag) = p.args.iter().find_map(|a| launcher_flag(a)) {
                return Err(self.err(
                    &format!("process.{name}.args"),
                    format!(
                        "{flag} is set by the launcher (the binary contract: {}); it may not be given in args",
                        LAUNCHER_FLAGS.join(" ")
                    ),
                ));
            }
            if let Some(v) = &p.variant
                && !p.variants.is_empty()
                && !p.variants.contains_key(v)
            {
                let known: Vec<_> = p.variants.keys().cloned().collect();
                return Err(self.err(
                    &format!("process.{name}.variant"),
                    format!("unknown variant {v:?}; the manifest defines {known:?}"),
                ));
            }
            for a in &p.after {
                if !self.processes.contains_key(a) {
                    return Err(self.err(
                        &format!("process.{name}.after"),
                        format!("no process named {a:?}"),
                    ));
                }
            }
            if let Some(r) = &p.restart {
                self.check_restart(name, r)?;
            }
            check_finite(&p.params).map_err(|k| {
                self.err(
                    &format!("process.{name}.params.{k}"),
                    "must be a finite number",
                )
            })?;
            for (v, t) in &p.variants {
                check_finite(t).map_err(|k| {
                    self.err(
                        &format!("process.{name}.variants.{v}.{k}"),
                        "must be a finite number",
                    )
                })?;
            }
        }
        self.check_after_cycles()
    }

    fn check_restart(&self, name: &str, r: &RestartSection) -> anyhow::Result<()> {
        let key = |k: &str| format!("process.{name}.restart.{k}");
        if RestartPolicy::parse(&r.policy).is_none() {
            return Err(self.err(
                &key("policy"),
                format!(
                    "unknown policy {:?}; expected \"never\", \"on-failure\" or \"always\"",
                    r.policy
                ),
            ));
        }
        if r.max == Some(0) {
            return Err(self.err(&key("max"), "must be at least 1 (use policy = \"never\")"));
        }
        if let Some(w) = r.window_s
            && !(w > 0.0 && w <= MAX_WINDOW_S)
        {
            return Err(self.err(
                &key("window_s"),
                format!("must be a number of seconds in (0, {MAX_WINDOW_S}], got {w:?}"),
            ));
        }
        if let Some([lo, hi]) = r.backoff_ms {
            if lo > hi {
                return Err(self.err(
                    &key("backoff_ms"),
                    format!("[first, longest] must not decrease, got [{lo}, {hi}]"),
                ));
            }
            if hi > MAX_BACKOFF_MS {
                return Err(self.err(
                    &key("backoff_ms"),
                    format!("the longest delay is at most {MAX_BACKOFF_MS} ms, got {hi}"),
                ));
            }
        }
        Ok(())
    }

    /// Refuses a cycle in `after`, naming it.
    fn check_after_cycles(&self) -> anyhow::Result<()> {
        // Depth-first search from every process; `path` is the current chain.
        fn visit<'a>(
            m: &'a Manifest,
            name: &'a str,
            path: &mut Vec<&'a str>,
            clear: &mut std::collections::BTreeSet<&'a str>,
        ) -> Option<Vec<&'a str>> {
            if clear.contains(name) {
                return None;
            }
            if let Some(i) = path.iter().position(|p| *p == name) {
                let mut cycle = path[i..].to_vec();
                cycle.push(name);
                return Some(cycle);
            }
            path.push(name);
            for a in &m.processes[name].after {
                if let Some(c) = visit(m, a, path, clear) {
                    return Some(c);
                }
            }
            path.pop();
            clear.insert(name);
            None
        }
        let mut clear = std::collections::BTreeSet::new();
        for name in self.processes.keys() {
            if let Some(cycle) = visit(self, name, &mut Vec::new(), &mut clear) {
                return Err(self.err(
                    &format!("process.{}.after", cycle[0]),
                    format!("cycle in `after`: {}", cycle.join(" -> ")),
                ));
            }
        }
        Ok(())
    }

    /// The clock mode of the run.
    pub fn clock(&self) -> ClockMode {
        // Checked in `check`.
        ClockMode::parse(&self.run.clock, self.run.rate).unwrap_or(ClockMode::Sim)
    }

    /// The effective manifest as TOML (after overrides), to hand to processes;
    /// `[run] source` names the file it came from.
    pub fn to_toml(&self) -> anyhow::Result<String> {
        let mut table = self.table.clone();
        if let Some(run) = table.get_mut("run").and_then(toml::Value::as_table_mut) {
            run.insert(
                "source".into(),
                toml::Value::String(self.path.display().to_string()),
            );
        }
        Ok(toml::to_string(&table)?)
    }

    /// The section of process `name`.
    pub fn process(&self, name: &str) -> anyhow::Result<&ProcessSection> {
        self.processes
            .get(name)
            .ok_or_else(|| anyhow::anyhow!("{}: no [process.{name}]", self.path.display()))
    }

    /// Parameters of process `name` for `variant`: the variant's table over the
    /// common `params`, deserialized into `T` (which should deny unknown fields).
    pub fn params<T: DeserializeOwned>(
        &self,
        name: &str,
        variant: Option<&str>,
    ) -> anyhow::Result<T> {
        let p = self.process(name)?;
        let mut merged = p.params.clone();
        let mut where_ = format!("process.{name}.params");
        let mut from_variant = None;
        if let Some(v) = variant.or(p.variant.as_deref()) {
            if let Some(t) = p.variants.get(v) {
                for (k, val) in t {
                    merged.insert(k.clone(), val.clone());
                }
                where_ = format!("process.{name}.params/variants.{v}");
                from_variant = Some((v, t));
            } else if !p.variants.is_empty() {
                bail!(
                    "{}: process.{name}: unknown variant {v:?}",
                    self.path.display()
                );
            }
        }
        toml::Table::try_into(merged).map_err(|e| {
            let msg = e.to_string();
            let msg = msg.trim_end();
            // The key the error is about, in the table that sets it (the
            // variant's over the common parameters), so that the error has
            // its line (or its override).
            let key = match param_key(msg) {
                Some(k) => {
                    let first = k.split('.').next().unwrap_or(&k);
                    match from_variant {
                        Some((v, t)) if t.contains_key(first) => {
                            format!("process.{name}.variants.{v}.{k}")
                        }
                        _ if p.params.contains_key(first) => format!("process.{name}.params.{k}"),
                        _ => where_.clone(),
                    }
                }
                None => where_.clone(),
            };
            let first_line = msg.lines().next().unwrap_or(msg);
            self.err(&key, first_line)
        })
    }
}

/// The dotted key a deserialization error of a parameter table is about:
/// the field of "unknown field `X`" inside the table "in `P`", or the value
/// "in `P`" itself.
fn param_key(msg: &str) -> Option<String> {
    let tick = |s: &str| -> Option<String> {
        let (_, rest) = s.split_once('`')?;
        Some(rest.split_once('`')?.0.to_owned())
    };
    let within = msg
        .lines()
        .find_map(|l| l.trim().strip_prefix("in ").and_then(tick));
    let first = msg.lines().next()?;
    if first.starts_with("unknown field") {
        let field = tick(first)?;
        Some(match within {
            Some(w) => format!("{w}.{field}"),
            None => field,
        })
    } else {
        within
    }
}

fn check_finite(t: &toml::Table) -> Result<(), String> {
    for (k, v) in t {
        match v {
            toml::Value::Float(f) if !f.is_finite() => return Err(k.clone()),
            toml::Value::Table(inner) => check_finite(inner).map_err(|sub| format!("{k}.{sub}"))?,
            _ => {}
        }
    }
    Ok(())
}

/// The 1-based line where the last component of a dotted `key` is set, if found.
fn line_of(text: &str, key: &str) -> Option<usize> {
    let last = key.rsplit('.').next()?;
    let section = key.rsplit_once('.').map(|(s, _)| s).unwrap_or("");
    let mut in_section = section.is_empty();
    // A key of a section the file does not have (added by `--set`) has no line.
    let mut section_seen = in_section;
    let mut fallback = None;
    for (i, line) in text.lines().enumerate() {
        let t = line.trim();
        if t.starts_with('[') {
            let name = t.trim_matches(|c| c == '[' || c == ']').trim();
            in_section = name == section || section.starts_with(&format!("{name}."));
            section_seen |= in_section;
            continue;
        }
        let Some((k, _)) = t.split_once('=') else {
            continue;
        };
        let k = k.trim();
        if k == last || k.ends_with(&format!(".{last}")) || sets_inline(t, last) {
            if in_section {
                return Some(i + 1);
            }
            fallback.get_or_insert(i + 1);
        }
    }
    fallback.filter(|_| section_seen)
}

/// The full dotted key an override sets: `run.rate`, `process.NAME.KEY`
/// (`NAME.KEY` is short for it).
fn override_key(spec: &str) -> String {
    let path = spec.split_once('=').map_or(spec, |(k, _)| k).trim();
    match path.split('.').next() {
        Some("run" | "site" | "process") => path.to_owned(),
        _ => format!("process.{path}"),
    }
}

/// Whether `line` sets `key` inside an inline table (`x = { key = 1 }`).
fn sets_inline(line: &str, key: &str) -> bool {
    let Some(brace) = line.find('{') else {
        return false;
    };
    let inner = &line[brace..];
    inner.match_indices(key).any(|(i, _)| {
        let before = inner[..i].chars().next_back();
        let after = inner[i + key.len()..].trim_start();
        before.is_some_and(|c| c == '{' || c == ',' || c.is_whitespace()) && after.starts_with('=')
    })
}

/// Applies `run.KEY=VALUE`, `site.KEY=VALUE`, `PROCESS.KEY=VALUE` or
/// `process.NAME.KEY=VALUE` (which may add a process) to the table; KEY may be dotted.
/// VALUE is read as TOML (`3`, `1.5`, `true`, `"x"`, `[1, 2]`), else as a string.
pub fn apply_override(table: &mut toml::Table, spec: &str) -> anyhow::Result<()> {
    let (path, value) = spec
        .split_once('=')
        .ok_or_else(|| anyhow::anyhow!("expected KEY=VALUE"))?;
    let value: toml::Value = format!("v = {value}")
        .parse::<toml::Table>()
        .ok()
        .and_then(|mut t| t.remove("v"))
        .unwrap_or_else(|| toml::Value::String(value.to_owned()));
    let mut parts: Vec<&str> = path.trim().split('.').collect();
    if parts.len() < 2 || parts.iter().any(|p| p.is_empty()) {
        bail!("expected run.KEY or PROCESS.KEY, got {path:?}");
    }
    // `process.NAME.KEY` may add a process; `NAME.KEY` changes an existing one.
    if parts[0] != "run" && parts[0] != "site" && parts[0] != "process" {
        if !table
            .get("process")
            .and_then(|p| p.as_table())
            .is_some_and(|p| p.contains_key(parts[0]))
        {
            bail!("no process named {:?} in the manifest", parts[0]);
        }
        parts.insert(0, "process");
    }
    let (last, dirs) = parts
        .split_last()
        .ok_or_else(|| anyhow::anyhow!("empty key"))?;
    let mut cur = table;
    for d in dirs {
        cur = cur
            .entry(d.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()))
            .as_table_mut()
            .ok_or_else(|| anyhow::anyhow!("{d} is not a table"))?;
    }
    cur.insert(last.to_string(), value);
    Ok(())
}

#[cfg(test)]
mod tests;
