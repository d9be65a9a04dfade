//! Stopping a run between frames: Ctrl-C and the signals that schedulers send.

/// Ctrl-C, SIGTERM (what schedulers and `timeout` send before they kill) or a hang-up finishes
/// the current frame, writes a checkpoint and exits with 130; a second one exits at once. A
/// hang-up that `nohup` ignores stays ignored.
pub fn stop_on_ctrl_c() {
    let hangup_ignored = hangup_is_ignored();
    let installed = ctrlc::set_handler(|| {
        if drapekit::run::INTERRUPTED.swap(true, std::sync::atomic::Ordering::SeqCst) {
            std::process::exit(130);
        }
        eprintln!("drapekit: stopping after this frame (a second Ctrl-C or signal quits now)");
    });
    if let Err(e) = installed {
        eprintln!("drapekit: warning: Ctrl-C will not write a checkpoint: {e}");
    }
    #[cfg(unix)]
    if hangup_ignored {
        // SAFETY: setting a signal's disposition to "ignore" runs no code in the handler.
        unsafe { libc::signal(libc::SIGHUP, libc::SIG_IGN) };
    }
}

/// Hang-ups are a unix signal.
#[cfg(not(unix))]
fn hangup_is_ignored() -> bool {
    false
}

/// Whether SIGHUP is ignored now (as `nohup` leaves it), which the Ctrl-C handler, installed
/// for hang-ups too, would undo.
#[cfg(unix)]
fn hangup_is_ignored() -> bool {
    // SAFETY: sigaction with a null new action only reads the current one into `old`.
    unsafe {
        let mut old: libc::sigaction = std::mem::zeroed();
        libc::sigaction(libc::SIGHUP, std::ptr::null(), &mut old) == 0
            && old.sa_sigaction == libc::SIG_IGN
    }
}
