//! The control service: a request from one node reaches the addressed process's
//! server, wakes it, and the answer comes back.

use std::sync::mpsc;
use std::time::Duration;

use nauta_messages::{ControlRequest, ControlResponse, Header, Role, command};
use nauta_runtime::{Context, ControlClient, ControlServer, EventLoop, Namespace, Wake};

#[test]
fn request_reaches_the_process_and_is_answered() {
    let ns = Namespace::unique();
    let (ready_tx, ready_rx) = mpsc::channel();
    let ns_server = ns.clone();
    let server = std::thread::spawn(move || -> anyhow::Result<u32> {
        let ctx = Context::new(&ns_server, Context::settings(Role::Attitude))?;
        let (mut control, inbox) = ControlServer::open(&ctx)?;
        ready_tx.send(()).ok();
        let mut got = 0;
        // Ticks are one hour apart: only the request's event can wake the loop.
        EventLoop::new(Duration::from_secs(3600)).run(&[&inbox], |wake| {
            assert_eq!(wake, Wake::Data);
            control.serve(|req| {
                got = req.command;
                ControlResponse {
                    header: Header::new(42, 0, Role::Attitude, 0),
                    status: 0,
                    state: 7,
                    last_stamp_ns: 42,
                }
            })?;
            Ok(if got != 0 {
                std::ops::ControlFlow::Break(())
            } else {
                std::ops::ControlFlow::Continue(())
            })
        })?;
        drop(control);
        drop(inbox);
        ctx.finish();
        Ok(got)
    });
    ready_rx
        .recv_timeout(Duration::from_secs(60))
        .expect("server started");
    let ctx = Context::new(&ns, Context::settings(Role::Launcher)).expect("client node");
    let client = ControlClient::open(&ctx, Role::Attitude, 0).expect("client");
    let req = ControlRequest {
        header: Header::new(0, 0, Role::Launcher, 0),
        command: command::SNAPSHOT_NOW,
        pad: 0,
        boundary_stamp_ns: 0,
    };
    let resp = client
        .request(&ctx, req, Duration::from_secs(60))
        .expect("answered");
    assert_eq!((resp.status, resp.state, resp.last_stamp_ns), (0, 7, 42));
    assert_eq!(
        server.join().expect("server thread").expect("server ran"),
        command::SNAPSHOT_NOW
    );
    drop(client);
    ctx.finish();
    let config = ns.config().expect("config");
    assert!(
        ns.all_files(&config).is_empty(),
        "{:?}",
        ns.all_files(&config)
    );
}
