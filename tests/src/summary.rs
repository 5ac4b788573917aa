//! The run summary `nauta launch --json` prints, read by the tests.

/// The run summary `nauta launch --json` prints on stdout: one JSON object
/// (keys in the README, "The run summary").
#[derive(Debug, Clone)]
pub struct Summary {
    /// The object.
    pub json: serde_json::Value,
}

impl std::fmt::Display for Summary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:#}", self.json)
    }
}

impl Summary {
    /// Parses `stdout`, which must be exactly one JSON object.
    pub fn parse(stdout: &str) -> Result<Self, String> {
        match serde_json::from_str::<serde_json::Value>(stdout.trim()) {
            Ok(json) if json.is_object() => Ok(Summary { json }),
            Ok(other) => Err(format!("the summary is not a JSON object: {other}")),
            Err(e) => Err(format!("stdout is not one JSON object: {e}")),
        }
    }

    fn u64_at(&self, pointer: &str) -> Option<u64> {
        self.json.pointer(pointer)?.as_u64()
    }

    fn f64_at(&self, pointer: &str) -> Option<f64> {
        self.json.pointer(pointer)?.as_f64()
    }

    fn str_at(&self, pointer: &str) -> Option<&str> {
        self.json.pointer(pointer)?.as_str()
    }

    /// The namespace of the run.
    pub fn namespace(&self) -> Option<&str> {
        self.str_at("/namespace")
    }

    /// Messages received on `service` (`streams.SERVICE.messages`).
    pub fn count(&self, service: &str) -> Option<u64> {
        self.json
            .get("streams")?
            .get(service)?
            .get("messages")?
            .as_u64()
    }

    /// Mean rate of `service`, Hz.
    pub fn rate_hz(&self, service: &str) -> Option<f64> {
        self.json
            .get("streams")?
            .get(service)?
            .get("rate_hz")?
            .as_f64()
    }

    /// Messages on every data service.
    pub fn messages(&self) -> Option<u64> {
        self.u64_at("/messages")
    }

    /// Sequence gaps seen by the launcher's taps.
    pub fn gaps(&self) -> Option<u64> {
        self.u64_at("/gaps")
    }

    /// Messages lost inside the processes.
    pub fn lost(&self) -> Option<u64> {
        self.u64_at("/lost")
    }

    /// Inputs refused by their checks.
    pub fn rejected(&self) -> Option<u64> {
        self.u64_at("/rejected")
    }

    /// The sensor stream's span: (service, simulated seconds, wall seconds)
    /// from its first to its last sample.
    pub fn sensor_span(&self) -> Option<(String, f64, f64)> {
        Some((
            self.str_at("/sensor_span/topic")?.to_owned(),
            self.f64_at("/sensor_span/simulated_s")?,
            self.f64_at("/sensor_span/wall_s")?,
        ))
    }

    /// Simulated seconds of the run.
    pub fn mission_s(&self) -> Option<f64> {
        self.f64_at("/mission_s")
    }

    /// The digest of `attitude/estimate`.
    pub fn digest(&self) -> Option<String> {
        self.digest_of("attitude/estimate")
    }

    /// The digest of estimate stream `topic` (hex).
    pub fn digest_of(&self, topic: &str) -> Option<String> {
        let d = self.json.get("digests")?.get(topic)?.as_str()?;
        (!d.is_empty() && d.chars().all(|c| c.is_ascii_hexdigit())).then(|| d.to_owned())
    }

    /// `nauta eval`'s `key` of estimate stream `topic` (`errors.TOPIC.KEY`).
    pub fn error(&self, topic: &str, key: &str) -> Option<f64> {
        self.json.get("errors")?.get(topic)?.get(key)?.as_f64()
    }

    /// Restarts of `process` (0 when it has none).
    pub fn restarts(&self, process: &str) -> u64 {
        self.per_process("restarts", process)
    }

    /// Swaps of `process` (0 when it has none).
    pub fn swaps(&self, process: &str) -> u64 {
        self.per_process("swaps", process)
    }

    /// `KEY.PROCESS` of a per-process count (absent: 0).
    fn per_process(&self, key: &str, process: &str) -> u64 {
        self.json
            .get(key)
            .and_then(|r| r.get(process))
            .and_then(serde_json::Value::as_u64)
            .unwrap_or(0)
    }

    /// True when every process exited 0 (`exit` is `ok`).
    pub fn all_exited_0(&self) -> bool {
        self.str_at("/exit") == Some("ok")
    }

    /// How the run ended: `end`, `signal` or `request`.
    pub fn stopped(&self) -> Option<&str> {
        self.str_at("/stopped")
    }

    /// The first failure, when the run failed.
    pub fn failure(&self) -> Option<&str> {
        self.str_at("/failure")
    }
}
