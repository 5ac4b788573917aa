//! Removing a run's files: never while one of its nodes lives, never a run that
//! is just starting, always once it is abandoned.

use std::time::Duration;

use nauta_messages::Role;
use nauta_runtime::{Context, Namespace, services};

#[test]
fn files_are_removed_only_when_the_run_is_over() {
    let ns = Namespace::unique();
    let ctx = Context::new(&ns, Context::settings(Role::Test)).expect("node");
    let publisher = ctx.publisher(&services::imu()).expect("publisher");
    assert!(!ns.shm_files().is_empty(), "a live run has files");

    // A live node protects the run, whatever the grace period.
    assert_eq!(ns.remove_if_unused().expect("checked"), 0);
    assert_eq!(ns.remove_if_abandoned(Duration::ZERO).expect("checked"), 0);
    assert!(!ns.shm_files().is_empty());

    // Leaving without `finish` keeps iceoryx2's per-namespace management segment.
    drop(publisher);
    drop(ctx);
    assert!(
        !ns.shm_files().is_empty(),
        "iceoryx2 keeps its management segment"
    );

    // Fresh files and no node: maybe a run being created; not touched.
    assert_eq!(
        ns.remove_if_abandoned(Duration::from_secs(3600))
            .expect("checked"),
        0
    );
    assert!(!ns.shm_files().is_empty());

    // Old enough (here: any age): abandoned, removed.
    assert!(ns.remove_if_abandoned(Duration::ZERO).expect("checked") > 0);
    let config = ns.config().expect("config");
    assert!(
        ns.all_files(&config).is_empty(),
        "{:?}",
        ns.all_files(&config)
    );
}

#[test]
fn finish_of_the_last_process_leaves_nothing() {
    let ns = Namespace::unique();
    let a = Context::new(&ns, Context::settings(Role::Sensor)).expect("node a");
    let mut s = Context::settings(Role::Attitude);
    s.process = "attitude".into();
    let b = Context::new(&ns, s).expect("node b");
    a.finish();
    assert!(!ns.shm_files().is_empty(), "b is still in the run");
    b.finish();
    let config = ns.config().expect("config");
    assert!(
        ns.all_files(&config).is_empty(),
        "{:?}",
        ns.all_files(&config)
    );
}
