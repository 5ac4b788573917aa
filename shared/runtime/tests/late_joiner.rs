//! A subscriber that joins late (a restarted estimator) receives the
//! service's history even from a publisher that has nothing new to send.
//! iceoryx2 delivers history only inside a send or an explicit
//! `update_connections`; found when a killed positioning came back
//! subscribed to an ains that was waiting for the positioning's watermark
//! and so published nothing: the cycle stalled for seconds and lost 6,000
//! `ains/nav` samples in `nauta bench chaos --manifest launch/complete.toml`
//! (the complete system's manifest then; `launch/survey.toml` since).

use std::sync::mpsc;
use std::time::{Duration, Instant};

use nauta_messages::{Header, Message, NavSolution, Role};
use nauta_runtime::{Connect, Context, Namespace, services};

#[test]
fn a_publisher_with_nothing_to_send_hands_its_history_to_a_late_subscriber() {
    let (done_tx, done_rx) = mpsc::channel::<()>();
    // Watchdog: a stuck test fails instead of hanging CI.
    std::thread::spawn(move || {
        // (A panic drops the sender: that is not a timeout.)
        if let Err(mpsc::RecvTimeoutError::Timeout) = done_rx.recv_timeout(Duration::from_secs(120))
        {
            eprintln!("watchdog: the test did not finish within 120 s");
            std::process::exit(101);
        }
    });
    let ns = Namespace::unique();
    let spec = services::nav_solution();
    let ctx = Context::new(&ns, Context::settings(Role::Ains)).expect("publisher node");
    let mut publisher = ctx.publisher(&spec).expect("publisher");
    let n = 5u64;
    for k in 0..n {
        let mut msg = NavSolution::default();
        *msg.header_mut() = Header::new((k + 1) * 10_000_000, 0, Role::Ains, 0);
        publisher.publish(msg).expect("publish");
    }
    publisher.flush();

    // The restarted consumer, in its own node, joins after the last send.
    let sub_ctx = Context::new(&ns, Context::settings(Role::Positioning)).expect("subscriber node");
    let (mut sub, inbox) = sub_ctx.subscriber(&spec).expect("subscriber");
    assert!(sub.connect().expect("connect"), "the publisher is there");

    // The publisher's event loop wakes with nothing to publish and flushes,
    // as the estimator shell does on every wake-up.
    publisher.flush();
    let mut stamps = Vec::new();
    let t0 = Instant::now();
    while (stamps.len() as u64) < n && t0.elapsed() < Duration::from_secs(10) {
        if inbox.wait(Duration::from_millis(100)) {
            sub.drain(|m| stamps.push(m.header().stamp_ns))
                .expect("drain");
        }
    }
    assert_eq!(
        stamps,
        (1..=n).map(|k| k * 10_000_000).collect::<Vec<_>>(),
        "the history, in order, woken by the flush"
    );
    drop(sub);
    drop(inbox);
    sub_ctx.finish();
    drop(publisher);
    ctx.finish();
    let _ = done_tx.send(());
}
