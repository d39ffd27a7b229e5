//! Waiting on one of ros2-client's futures from a node's plain thread, with a deadline.

/// Run `f` to completion on this thread, or give up after `timeout` (None).
pub fn block_on_within<F: std::future::Future>(
    f: F,
    timeout: std::time::Duration,
) -> Option<F::Output> {
    let (expire, expired) = futures::channel::oneshot::channel::<()>();
    std::thread::spawn(move || {
        std::thread::sleep(timeout);
        let _ = expire.send(());
    });
    futures::executor::block_on(async move {
        futures::pin_mut!(f);
        match futures::future::select(f, expired).await {
            futures::future::Either::Left((output, _)) => Some(output),
            futures::future::Either::Right(_) => None,
        }
    })
}
