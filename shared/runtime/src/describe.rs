//! `--describe`: a binary's inputs and outputs, so the launcher can check the
//! wiring of a manifest without the manifest repeating it (DESIGN §5).

use serde::{Deserialize, Serialize};

use nauta_messages::Message;

use crate::services::ServiceSpec;

/// One port: service name (without namespace) and type name.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct PortDescription {
    /// Service name, e.g. `sensor/imu`.
    pub service: String,
    /// Pinned type name, e.g. `nauta.ImuSample.v1`.
    #[serde(rename = "type")]
    pub type_name: String,
    /// An input the process can run without: the wiring check accepts it
    /// when nobody publishes it (e.g. the sensor's `lbl/interrogate`).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub optional: bool,
}

impl PortDescription {
    /// The description of a service.
    pub fn of<M: Message>(spec: &ServiceSpec<M>) -> Self {
        PortDescription {
            service: spec.name.clone(),
            type_name: M::TYPE_NAME.to_owned(),
            optional: false,
        }
    }

    /// An optional input (see [`PortDescription::optional`]).
    pub fn optional<M: Message>(spec: &ServiceSpec<M>) -> Self {
        PortDescription {
            optional: true,
            ..Self::of(spec)
        }
    }
}

/// What `--describe` prints.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Describe {
    /// The role (`attitude`).
    pub role: String,
    /// Services it subscribes to.
    pub inputs: Vec<PortDescription>,
    /// Services it publishes.
    pub outputs: Vec<PortDescription>,
    /// Variants it implements; the first is the default.
    pub variants: Vec<String>,
    /// A data source: it produces data on its own (its inputs, if any, are
    /// feedback such as LBL interrogations), so the launcher starts it in
    /// standby and activates it once every process is ready. A process
    /// without inputs is always a source, except the logger, whose inputs are
    /// whatever services the run has (it discovers them).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub source: bool,
}

impl Describe {
    /// Whether the launcher must start this process in standby (see
    /// [`Describe::source`]).
    pub fn is_source(&self) -> bool {
        self.source || (self.inputs.is_empty() && self.role != nauta_messages::Role::Logger.name())
    }
}

impl Describe {
    /// Prints the description as one line of JSON on stdout.
    pub fn print(&self) -> anyhow::Result<()> {
        println!("{}", serde_json::to_string(self)?);
        Ok(())
    }
}
