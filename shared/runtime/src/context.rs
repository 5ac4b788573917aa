//! A process's connection to its run: one iceoryx2 node in the run's namespace,
//! the run settings from the manifest, and the functions that open ports with the
//! QoS fixed in [`crate::services`].

use std::cell::Cell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use anyhow::Context as _;
use iceoryx2::config::Config;
use iceoryx2::node::NodeWaitFailure;
use iceoryx2::port::BackpressureAction;
use iceoryx2::port::backpressure_strategy::BackpressureStrategy;
use iceoryx2::prelude::*;
use nauta_messages::{Header, Message, Role, RunEvent, event_kind, to_fixed_str};

use crate::Ipc;
use crate::clock::ClockMode;
use crate::manifest::Manifest;
use crate::namespace::{CleanupReport, Namespace, cleanup_dead_nodes};
use crate::ports::{
    Connect, DEFAULT_BACKPRESSURE_DEADLINE, GapCounter, Inbox, Publisher, Subscriber,
};
use crate::process::ProcessArgs;
use crate::services::{self, Delivery, MAX_NODES, MAX_SUBSCRIBERS, ServiceSpec};

/// Prefix of every nauta service name.
pub const SERVICE_PREFIX: &str = "nauta/";

/// Settings of a context that does not come from a manifest (tests, benchmarks).
#[derive(Debug, Clone)]
pub struct ContextSettings {
    /// Role of the process.
    pub role: Role,
    /// Name of the process.
    pub process: String,
    /// Instance number.
    pub instance: u32,
    /// Variant.
    pub variant: String,
    /// Clock.
    pub clock: ClockMode,
    /// Back-pressure deadline in `sim` mode.
    pub deadline: Duration,
}

/// A process's node, run settings and port factory.
pub struct Context {
    /// The iceoryx2 node of this process.
    pub node: Node<Ipc>,
    /// The run's iceoryx2 configuration (namespace prefix).
    pub config: Config,
    /// The run's namespace.
    pub namespace: Namespace,
    /// The run's clock.
    pub clock: ClockMode,
    /// This process's role.
    pub role: Role,
    /// Name in the manifest.
    pub process: String,
    /// Instance number.
    pub instance: u32,
    /// Variant running.
    pub variant: String,
    /// Start in standby.
    pub standby: bool,
    /// Warm-start snapshot file (`--snapshot`), see [`Context::warm_start`].
    pub snapshot_file: Option<std::path::PathBuf>,
    /// Publish nothing stamped at or before this (`--resume-after`).
    pub resume_after_ns: Option<u64>,
    /// Optional inputs nobody publishes in this run (`--absent`).
    pub absent: Vec<String>,
    /// The manifest, when started from one.
    pub manifest: Option<Manifest>,
    /// Back-pressure deadline in `sim` mode.
    pub deadline: Duration,
    started: Instant,
    gave_up: Rc<Cell<bool>>,
    events: Option<Publisher<RunEvent>>,
}

impl std::fmt::Debug for Context {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Context")
            .field("namespace", &self.namespace)
            .field("process", &self.process)
            .field("role", &self.role)
            .field("instance", &self.instance)
            .field("clock", &self.clock)
            .finish()
    }
}

impl Context {
    /// The context of a service binary started by the launcher (binary contract).
    pub fn from_args(
        role: Role,
        args: &ProcessArgs,
        default_variant: &str,
    ) -> anyhow::Result<Self> {
        let manifest_path = args.manifest.as_ref().context("--manifest is required")?;
        let manifest = Manifest::load(manifest_path)?;
        let ns = args
            .namespace
            .as_deref()
            .context("--namespace is required")?;
        let namespace = Namespace::new(ns)?;
        let process = args
            .process
            .clone()
            .unwrap_or_else(|| role.name().to_owned());
        let section = manifest.process(&process)?;
        let variant = args
            .variant
            .clone()
            .or_else(|| section.variant.clone())
            .unwrap_or_else(|| default_variant.to_owned());
        let settings = ContextSettings {
            role,
            process,
            instance: args.instance,
            variant,
            clock: manifest.clock(),
            deadline: Duration::from_millis(manifest.run.backpressure_deadline_ms),
        };
        let mut ctx = Self::new(&namespace, settings)?;
        ctx.standby = args.standby;
        ctx.snapshot_file = args.snapshot.clone();
        ctx.resume_after_ns = args.resume_after;
        ctx.absent = args.absent.clone();
        ctx.manifest = Some(manifest);
        Ok(ctx)
    }

    /// A context without a manifest.
    pub fn new(namespace: &Namespace, s: ContextSettings) -> anyhow::Result<Self> {
        let config = namespace.config()?;
        let name = format!("{}-{}", s.process, s.instance);
        let node = NodeBuilder::new()
            .name(&NodeName::new(&name).map_err(|e| anyhow::anyhow!("node name {name:?}: {e:?}"))?)
            .config(&config)
            .create::<Ipc>()
            .map_err(|e| anyhow::anyhow!("cannot create the iceoryx2 node of {name}: {e:?}"))?;
        namespace.secure_shared_memory()?;
        let mut ctx = Context {
            node,
            config,
            namespace: namespace.clone(),
            clock: s.clock,
            role: s.role,
            process: s.process,
            instance: s.instance,
            variant: s.variant,
            standby: false,
            snapshot_file: None,
            resume_after_ns: None,
            absent: Vec::new(),
            manifest: None,
            deadline: s.deadline,
            started: Instant::now(),
            gave_up: Rc::new(Cell::new(false)),
            events: None,
        };
        ctx.events = Some(ctx.publisher(&services::run_events())?);
        Ok(ctx)
    }

    /// Settings with defaults for `role` (sim clock, instance 0).
    pub fn settings(role: Role) -> ContextSettings {
        ContextSettings {
            role,
            process: role.name().to_owned(),
            instance: 0,
            variant: String::new(),
            clock: ClockMode::Sim,
            deadline: DEFAULT_BACKPRESSURE_DEADLINE,
        }
    }

    /// The manifest this process was started from.
    pub fn manifest(&self) -> anyhow::Result<&Manifest> {
        self.manifest
            .as_ref()
            .context("this process was not started from a manifest")
    }

    /// This process's parameters from the manifest (see [`Manifest::params`]).
    pub fn params<T: serde::de::DeserializeOwned>(&self) -> anyhow::Result<T> {
        self.manifest()?.params(&self.process, Some(&self.variant))
    }

    /// Wall time since the process started.
    pub fn uptime(&self) -> Duration {
        self.started.elapsed()
    }

    fn lossless(&self, spec_delivery: Delivery) -> bool {
        spec_delivery == Delivery::ByClock && self.clock.is_lossless()
    }

    fn open_pubsub<M: Message>(
        &self,
        spec: &ServiceSpec<M>,
    ) -> anyhow::Result<iceoryx2::service::port_factory::publish_subscribe::PortFactory<Ipc, M, ()>>
    {
        let name = service_name(&spec.name)?;
        self.node
            .service_builder(&name)
            .publish_subscribe::<M>()
            .enable_safe_overflow(!self.lossless(spec.delivery))
            .subscriber_max_buffer_size(spec.buffer)
            .history_size(spec.history)
            .max_publishers(spec.max_publishers)
            .max_subscribers(MAX_SUBSCRIBERS)
            .max_nodes(MAX_NODES)
            .open_or_create()
            .map_err(|e| {
                anyhow::anyhow!(
                    "cannot open service {} ({}): {e:?}",
                    spec.name,
                    M::TYPE_NAME
                )
            })
    }

    fn open_event<M: Message>(
        &self,
        spec: &ServiceSpec<M>,
    ) -> anyhow::Result<iceoryx2::service::port_factory::event::PortFactory<Ipc>> {
        let name = service_name(&spec.name)?;
        self.node
            .service_builder(&name)
            .event()
            .max_notifiers(spec.max_publishers)
            .max_listeners(MAX_SUBSCRIBERS)
            .max_nodes(MAX_NODES)
            .open_or_create()
            .map_err(|e| anyhow::anyhow!("cannot open event service {}: {e:?}", spec.name))
    }

    /// Opens a publisher on `spec`.
    pub fn publisher<M: Message>(&self, spec: &ServiceSpec<M>) -> anyhow::Result<Publisher<M>> {
        let service = self.open_pubsub(spec)?;
        let deadline = self.deadline;
        let inner = service
            .publisher_builder()
            .backpressure_strategy(BackpressureStrategy::RetryUntilDelivered)
            .set_backpressure_handler(move |info: &iceoryx2::port::BackpressureInfo| {
                if info.elapsed_time >= deadline {
                    BackpressureAction::DiscardDataAndFail
                } else {
                    BackpressureAction::Retry
                }
            })
            .create()
            .map_err(|e| anyhow::anyhow!("cannot create a publisher on {}: {e:?}", spec.name))?;
        let notifier = self
            .open_event(spec)?
            .notifier_builder()
            .create()
            .map_err(|e| anyhow::anyhow!("cannot create a notifier on {}: {e:?}", spec.name))?;
        Ok(Publisher {
            service,
            inner,
            notifier,
            name: spec.name.clone(),
            role: self.role,
            instance: self.instance,
            config: self.config.clone(),
            seq: 0,
            pending: false,
            unnotified: 0,
            notify_every: (spec.buffer / 2).max(1),
            published: 0,
            given_up: 0,
            gave_up_flag: self.gave_up.clone(),
            subscribers_seen: 0,
        })
    }

    /// Opens a subscriber on `spec` and the inbox that wakes on its publishers.
    pub fn subscriber<M: Message>(
        &self,
        spec: &ServiceSpec<M>,
    ) -> anyhow::Result<(Subscriber<M>, Inbox)> {
        let service = self.open_pubsub(spec)?;
        let inner = service
            .subscriber_builder()
            .create()
            .map_err(|e| anyhow::anyhow!("cannot create a subscriber on {}: {e:?}", spec.name))?;
        let listener = self
            .open_event(spec)?
            .listener_builder()
            .create()
            .map_err(|e| anyhow::anyhow!("cannot create a listener on {}: {e:?}", spec.name))?;
        Ok((
            Subscriber {
                service,
                inner,
                name: spec.name.clone(),
                received: 0,
                gaps: GapCounter::default(),
            },
            Inbox {
                listener,
                name: spec.name.clone(),
            },
        ))
    }

    /// Publishes a run event about this process (`event_kind::READY`, ...).
    pub fn announce(&mut self, kind: u32, stamp_ns: u64, exit_code: i32) {
        let ev = RunEvent {
            header: Header::new(stamp_ns, 0, self.role, self.instance),
            kind,
            role: self.role as u32,
            instance: self.instance,
            pid: std::process::id(),
            exit_code,
            pad: 0,
            process: to_fixed_str(&self.process),
            variant: to_fixed_str(&self.variant),
        };
        if let Some(p) = self.events.as_mut()
            && let Err(e) = p.publish_now(ev)
        {
            tracing::warn!(error = %e, "cannot publish run event");
        }
    }

    /// The warm-start snapshot the launcher handed over (`--snapshot`), if
    /// any: the role's snapshot message, decoded. A file that cannot be read
    /// or decoded is an error (the caller decides whether to start cold).
    pub fn warm_start<M: Message>(&self) -> anyhow::Result<Option<M>> {
        let Some(path) = &self.snapshot_file else {
            return Ok(None);
        };
        let bytes = std::fs::read(path)
            .with_context(|| format!("cannot read the snapshot {}", path.display()))?;
        nauta_messages::codec::decode::<M>(&bytes)
            .map(Some)
            .map_err(|e| anyhow::anyhow!("snapshot {}: {e}", path.display()))
    }

    /// Publishes a run event about another process (the launcher's restarts,
    /// exits and swaps).
    pub fn publish_event(&mut self, ev: RunEvent) {
        if let Some(p) = self.events.as_mut()
            && let Err(e) = p.publish_now(ev)
        {
            tracing::warn!(error = %e, "cannot publish run event");
        }
    }

    /// Waits until every input has a publisher and is attached to it (see
    /// [`Connect`]), then reports ready. Returns false if a termination signal
    /// arrived first.
    pub fn connect_and_ready(&mut self, inputs: &[&dyn Connect]) -> anyhow::Result<bool> {
        let t0 = Instant::now();
        let mut warned = false;
        loop {
            let mut all = true;
            for i in inputs {
                all &= i.connect()?;
            }
            if all {
                break;
            }
            if !warned && t0.elapsed() > Duration::from_secs(5) {
                let missing: Vec<&str> = inputs
                    .iter()
                    .filter(|i| !matches!(i.connect(), Ok(true)))
                    .map(|i| i.service())
                    .collect();
                tracing::warn!(?missing, "still waiting for publishers");
                warned = true;
            }
            if !self.sleep(Duration::from_millis(1)) {
                return Ok(false);
            }
        }
        self.ready();
        Ok(true)
    }

    /// Announces that this process has opened its ports (and connected its
    /// inputs) and is ready.
    pub fn ready(&mut self) {
        self.announce(event_kind::READY, 0, 0);
        tracing::info!(process = %self.process, variant = %self.variant, "ready");
    }

    /// Removes the resources of dead nodes of this run.
    pub fn cleanup_dead_nodes(&self) -> CleanupReport {
        match cleanup_dead_nodes(&self.config) {
            Ok(r) => r,
            Err(e) => {
                tracing::warn!(error = %e, "dead-node cleanup failed");
                CleanupReport::default()
            }
        }
    }

    /// True once any publisher of this process gave a delivery up at its deadline.
    pub fn any_delivery_given_up(&self) -> bool {
        self.gave_up.get()
    }

    /// Checks for SIGINT/SIGTERM without blocking (for sources that never wait).
    /// An interrupted wait (EINTR) is not a termination request.
    pub fn termination_requested(&self) -> bool {
        matches!(
            self.node.wait(Duration::ZERO),
            Err(NodeWaitFailure::TerminationRequest)
        )
    }

    /// Leaves the run: drops the node and, if this was the last live node of the
    /// namespace, removes what is left of the run (see
    /// [`Namespace::remove_if_unused`]). Drop every port first.
    pub fn finish(self) {
        let namespace = self.namespace.clone();
        drop(self);
        if let Err(e) = namespace.remove_if_unused() {
            tracing::debug!(error = %e, "run resources not removed");
        }
    }

    /// Sleeps up to `d`, returning false when a termination signal (SIGINT,
    /// SIGTERM) arrived. A sleep interrupted by another signal (EINTR:
    /// SIGSTOP/SIGCONT, SIGCHLD, a debugger) ends early and returns true.
    pub fn sleep(&self, d: Duration) -> bool {
        match self.node.wait(d) {
            Ok(()) => true,
            Err(NodeWaitFailure::TerminationRequest) => false,
            // iceoryx2 keeps a SIGINT/SIGTERM that interrupted the sleep:
            // the next check reports it.
            Err(NodeWaitFailure::Interrupt) => !self.termination_requested(),
        }
    }
}

/// The full iceoryx2 service name of a nauta service.
pub fn service_name(name: &str) -> anyhow::Result<ServiceName> {
    let full = format!("{SERVICE_PREFIX}{name}");
    ServiceName::new(&full).map_err(|e| anyhow::anyhow!("invalid service name {full:?}: {e:?}"))
}
