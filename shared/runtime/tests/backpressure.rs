//! A publisher's long batch in `sim` clock (lossless): the subscriber is woken
//! before its queue fills, so a batch longer than the queue is delivered
//! whole instead of blocking the publisher on a subscriber that was never
//! told to drain (found when the aided INS began to consume the attitude's
//! 100 Hz estimates: every 2 s the pipeline stalled to the deadline and lost
//! a sample).

use std::sync::mpsc;
use std::time::{Duration, Instant};

use nauta_messages::{Header, ImuSample, Message, Role};
use nauta_runtime::{Connect, Context, Namespace, services};

#[test]
fn a_batch_longer_than_the_subscriber_queue_is_delivered_without_giving_up() {
    batch_is_delivered(services::imu().buffer + 8);
}

/// A batch that ends exactly where the publisher notifies on its own: its
/// last message must still be notified by the batch's flush.
#[test]
fn a_batch_of_half_a_queue_is_delivered_whole() {
    batch_is_delivered(services::imu().buffer / 2);
    batch_is_delivered(services::imu().buffer);
}

fn batch_is_delivered(n: usize) {
    let (done_tx, done_rx) = mpsc::channel::<()>();
    // Watchdog: a stuck test fails instead of hanging CI.
    std::thread::spawn(move || {
        if done_rx.recv_timeout(Duration::from_secs(120)).is_err() {
            eprintln!("watchdog: the test did not finish within 120 s");
            std::process::exit(101);
        }
    });
    let ns = Namespace::unique();
    let spec = services::imu();
    let mut settings = Context::settings(Role::Sensor);
    settings.deadline = Duration::from_millis(500);
    let ctx = Context::new(&ns, settings).expect("publisher node");
    let mut publisher = ctx.publisher(&spec).expect("publisher");

    let (ready_tx, ready_rx) = mpsc::channel();
    let sub_ns = ns.clone();
    let reader = std::thread::spawn(move || {
        let ctx =
            Context::new(&sub_ns, Context::settings(Role::Attitude)).expect("subscriber node");
        let (mut sub, inbox) = ctx.subscriber(&services::imu()).expect("subscriber");
        while !sub.connect().expect("connect") {
            std::thread::sleep(Duration::from_millis(1));
        }
        ready_tx.send(()).expect("ready");
        let mut stamps = Vec::new();
        let t0 = Instant::now();
        while stamps.len() < n && t0.elapsed() < Duration::from_secs(60) {
            // Drains when woken, as a role's event loop does.
            if inbox.wait(Duration::from_millis(100)) {
                sub.drain(|m: ImuSample| stamps.push(m.header().stamp_ns))
                    .expect("drain");
            }
        }
        stamps
    });
    ready_rx.recv().expect("subscriber ready");
    // One batch, no flush in between: as an estimator publishes what one
    // wake-up produced.
    for k in 0..n as u64 {
        let msg = ImuSample {
            header: Header::new((k + 1) * 10_000_000, 0, Role::Sensor, 0),
            interval_s: 0.01,
            ..Default::default()
        };
        publisher.publish(msg).expect("publish");
    }
    publisher.flush();
    let stamps = reader.join().expect("subscriber thread");
    assert_eq!(
        publisher.given_up(),
        0,
        "deliveries given up at the deadline"
    );
    assert_eq!(stamps.len(), n, "messages received");
    assert!(stamps.windows(2).all(|w| w[1] > w[0]), "in order");
    drop(publisher);
    ctx.finish();
    let _ = done_tx.send(());
}
