//! Finding the run's services: iceoryx2's service list of the run's namespace,
//! matched against nauta's service definitions (name and message type).

use std::collections::BTreeSet;

use iceoryx2::prelude::*;
use nauta_log::LogWriter;
use nauta_runtime::context::SERVICE_PREFIX;
use nauta_runtime::ports::Inbox;
use nauta_runtime::{Context, Ipc, services};

use crate::taps::{self, RecordingTap};

/// The run's publish-subscribe services now: (name without namespace and
/// prefix, payload type name).
fn list(ctx: &Context) -> anyhow::Result<Vec<(String, String)>> {
    let mut found = Vec::new();
    <Ipc as iceoryx2::service::Service>::list(&ctx.config, |s| {
        let st = &s.static_details;
        if let iceoryx2::service::static_config::messaging_pattern::MessagingPattern::PublishSubscribe(ps) =
            st.messaging_pattern()
            && let Some(name) = st.name().as_str().strip_prefix(SERVICE_PREFIX)
        {
            found.push((
                name.to_owned(),
                ps.message_type_details().payload.type_name().to_string(),
            ));
        }
        CallbackProgression::Continue
    })
    .map_err(|e| anyhow::anyhow!("cannot list the run's services: {e:?}"))?;
    found.sort();
    Ok(found)
}

/// Subscribes to every service of the run not yet in `known` whose name and
/// type nauta defines; returns the new subscriptions. A service nauta does not
/// define is reported once and skipped.
pub fn open_new(
    ctx: &Context,
    writer: &mut LogWriter,
    known: &mut BTreeSet<String>,
) -> anyhow::Result<Vec<(Box<dyn RecordingTap>, Inbox)>> {
    let defined = services::all();
    let mut out = Vec::new();
    for (name, type_name) in list(ctx)? {
        if known.contains(&name) {
            continue;
        }
        known.insert(name.clone());
        match defined.iter().find(|s| s.name == name) {
            Some(spec) if spec.type_name == type_name => {
                out.push(taps::open(ctx, writer, &name, &type_name)?);
            }
            Some(spec) => tracing::warn!(
                service = %name,
                carries = %type_name,
                defined = spec.type_name,
                "service carries another type than its definition; not recorded"
            ),
            None => {
                tracing::warn!(service = %name, r#type = %type_name, "unknown service; not recorded")
            }
        }
    }
    Ok(out)
}
