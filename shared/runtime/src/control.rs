//! `<role>/control/<instance>`: the launcher's commands to one process
//! (standby, activate, deactivate, snapshot-now, stop), over iceoryx2
//! request-response, with a companion event so that a request wakes the
//! process's [`crate::EventLoop`] at once.

use std::time::{Duration, Instant};

use iceoryx2::port::client::Client;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::server::Server;
use nauta_messages::{
    ControlRequest, ControlResponse, Message, PipelineRequest, PipelineResponse, Role,
    control_service,
};

use crate::Ipc;
use crate::context::{Context, service_name};
use crate::ports::Inbox;
use crate::services::{MAX_NODES, MAX_SUBSCRIBERS};

/// The control service name of one process: `<role>/control/<instance>`.
pub fn control_name(role: Role, instance: u32) -> String {
    format!("{}/{instance}", control_service(role.name()))
}

/// The launcher's own control service, for `nauta stop|restart|swap`.
pub fn pipeline_control_name() -> String {
    control_name(Role::Launcher, 0)
}

type ReqRes<Req, Res> =
    iceoryx2::service::port_factory::request_response::PortFactory<Ipc, Req, (), Res, ()>;

fn open<Req: Message, Res: Message>(
    ctx: &Context,
    name: &str,
) -> anyhow::Result<(
    ReqRes<Req, Res>,
    iceoryx2::service::port_factory::event::PortFactory<Ipc>,
)> {
    let sn = service_name(name)?;
    let rr = ctx
        .node
        .service_builder(&sn)
        .request_response::<Req, Res>()
        .max_servers(2)
        .max_clients(4)
        .max_nodes(MAX_NODES)
        .open_or_create()
        .map_err(|e| anyhow::anyhow!("cannot open control service {name}: {e:?}"))?;
    let ev = ctx
        .node
        .service_builder(&sn)
        .event()
        .max_notifiers(4)
        .max_listeners(MAX_SUBSCRIBERS)
        .max_nodes(MAX_NODES)
        .open_or_create()
        .map_err(|e| anyhow::anyhow!("cannot open control event {name}: {e:?}"))?;
    Ok((rr, ev))
}

/// The serving side, in the controlled process.
pub struct ControlServer<Req: Message = ControlRequest, Res: Message = ControlResponse> {
    _service: ReqRes<Req, Res>,
    server: Server<Ipc, Req, (), Res, ()>,
    name: String,
}

/// The launcher's server for `nauta stop|restart|swap`.
pub type PipelineServer = ControlServer<PipelineRequest, PipelineResponse>;
/// The client of [`PipelineServer`].
pub type PipelineClient = ControlClient<PipelineRequest, PipelineResponse>;

impl<Req: Message, Res: Message> std::fmt::Debug for ControlServer<Req, Res> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ControlServer")
            .field("service", &self.name)
            .finish()
    }
}

impl ControlServer {
    /// Opens this process's control service and the inbox that wakes on requests.
    pub fn open(ctx: &Context) -> anyhow::Result<(Self, Inbox)> {
        Self::open_named(ctx, &control_name(ctx.role, ctx.instance))
    }
}

impl<Req: Message, Res: Message> ControlServer<Req, Res> {
    /// Opens the control service `name` and the inbox that wakes on requests.
    pub fn open_named(ctx: &Context, name: &str) -> anyhow::Result<(Self, Inbox)> {
        let name = name.to_owned();
        let (rr, ev) = open::<Req, Res>(ctx, &name)?;
        let server = rr
            .server_builder()
            .create()
            .map_err(|e| anyhow::anyhow!("cannot serve {name}: {e:?}"))?;
        let listener = ev
            .listener_builder()
            .create()
            .map_err(|e| anyhow::anyhow!("cannot listen on {name}: {e:?}"))?;
        Ok((
            ControlServer {
                _service: rr,
                server,
                name: name.clone(),
            },
            Inbox { listener, name },
        ))
    }

    /// Answers every pending request with `handle`; returns how many.
    pub fn serve(&mut self, mut handle: impl FnMut(&Req) -> Res) -> anyhow::Result<usize> {
        let mut n = 0;
        while let Some(active) = self
            .server
            .receive()
            .map_err(|e| anyhow::anyhow!("{}: {e:?}", self.name))?
        {
            let response = handle(active.payload());
            if let Err(e) = active.send_copy(response) {
                tracing::warn!(service = %self.name, error = ?e, "control response not sent");
            }
            n += 1;
        }
        Ok(n)
    }
}

/// The commanding side (the launcher, `nauta restart|swap|stop`).
pub struct ControlClient<Req: Message = ControlRequest, Res: Message = ControlResponse> {
    _service: ReqRes<Req, Res>,
    client: Client<Ipc, Req, (), Res, ()>,
    notifier: Notifier<Ipc>,
    name: String,
}

impl<Req: Message, Res: Message> std::fmt::Debug for ControlClient<Req, Res> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ControlClient")
            .field("service", &self.name)
            .finish()
    }
}

impl ControlClient {
    /// Opens the control service of process `role`/`instance`.
    pub fn open(ctx: &Context, role: Role, instance: u32) -> anyhow::Result<Self> {
        Self::open_named(ctx, &control_name(role, instance))
    }
}

impl<Req: Message, Res: Message> ControlClient<Req, Res> {
    /// Opens the control service `name`.
    pub fn open_named(ctx: &Context, name: &str) -> anyhow::Result<Self> {
        let name = name.to_owned();
        let (rr, ev) = open::<Req, Res>(ctx, &name)?;
        let client = rr
            .client_builder()
            .create()
            .map_err(|e| anyhow::anyhow!("cannot create a client on {name}: {e:?}"))?;
        let notifier = ev
            .notifier_builder()
            .create()
            .map_err(|e| anyhow::anyhow!("cannot notify {name}: {e:?}"))?;
        Ok(ControlClient {
            _service: rr,
            client,
            notifier,
            name,
        })
    }

    /// Sends `request` without waiting: poll the answer with
    /// [`Pending::poll`] (a launcher must keep draining its inputs meanwhile).
    pub fn send(&self, request: Req) -> anyhow::Result<Pending<Req, Res>> {
        let inner = self
            .client
            .send_copy(request)
            .map_err(|e| anyhow::anyhow!("{}: request not sent: {e:?}", self.name))?;
        let _ = self.notifier.notify();
        Ok(Pending {
            inner,
            name: self.name.clone(),
        })
    }

    /// Sends `request` and waits up to `timeout` for the answer.
    pub fn request(&self, ctx: &Context, request: Req, timeout: Duration) -> anyhow::Result<Res> {
        let pending = self
            .client
            .send_copy(request)
            .map_err(|e| anyhow::anyhow!("{}: request not sent: {e:?}", self.name))?;
        let _ = self.notifier.notify();
        let t0 = Instant::now();
        loop {
            if let Some(r) = pending
                .receive()
                .map_err(|e| anyhow::anyhow!("{}: {e:?}", self.name))?
            {
                return Ok(*r.payload());
            }
            anyhow::ensure!(
                t0.elapsed() < timeout,
                "{}: no answer within {timeout:?}",
                self.name
            );
            anyhow::ensure!(ctx.sleep(Duration::from_millis(1)), "interrupted");
        }
    }
}

/// A request sent with [`ControlClient::send`], its answer not yet read.
pub struct Pending<Req: Message, Res: Message> {
    inner: iceoryx2::pending_response::PendingResponse<Ipc, Req, (), Res, ()>,
    name: String,
}

impl<Req: Message, Res: Message> std::fmt::Debug for Pending<Req, Res> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Pending")
            .field("service", &self.name)
            .finish()
    }
}

impl<Req: Message, Res: Message> Pending<Req, Res> {
    /// The answer, if it has arrived.
    pub fn poll(&self) -> anyhow::Result<Option<Res>> {
        Ok(self
            .inner
            .receive()
            .map_err(|e| anyhow::anyhow!("{}: {e:?}", self.name))?
            .map(|r| *r.payload()))
    }
}
