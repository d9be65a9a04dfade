//! What a run says on stderr besides its progress bars: warnings and notes. Batch items run
//! side by side and their lines interleave, so each line names the item its thread runs.

use std::cell::RefCell;

thread_local! {
    /// The batch item this thread runs, if any.
    static ITEM: RefCell<Option<String>> = const { RefCell::new(None) };
}

/// Runs `f` with this thread's warnings and notes labelled as batch item `id`'s. The label
/// goes when `f` returns or unwinds, so that the thread's next item is not named after it.
pub fn as_item<T>(id: &str, f: impl FnOnce() -> T) -> T {
    struct Unlabel;
    impl Drop for Unlabel {
        fn drop(&mut self) {
            ITEM.with(|item| *item.borrow_mut() = None);
        }
    }
    ITEM.with(|item| *item.borrow_mut() = Some(id.to_string()));
    let _unlabel = Unlabel;
    f()
}

/// Names the batch item in the report of a panic on its thread: installs, once, a panic hook
/// that reports such a panic as one line, `drapekit: item ID: panicked at FILE:LINE: MESSAGE`,
/// and hands a panic on any other thread to the hook that was there (Rust's report, with its
/// backtrace when asked for: rerun the item's scene alone with `drapekit run` for that).
pub fn label_panics() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            let label = label();
            if label.is_empty() {
                return previous(info);
            }
            let at = info
                .location()
                .map_or(String::new(), |l| format!(" at {l}"));
            let payload = info.payload();
            let message = (payload.downcast_ref::<&str>().copied())
                .or_else(|| payload.downcast_ref::<String>().map(String::as_str))
                .unwrap_or("(no message)");
            eprintln!("drapekit: {label}panicked{at}: {message}");
        }));
    });
}

/// A warning on stderr: `drapekit: warning: [item ID: ]w`.
pub fn warn(w: &str) {
    eprintln!("drapekit: warning: {}{w}", label());
}

/// A note on stderr: `drapekit: [item ID: ]n`.
pub fn note(n: &str) {
    eprintln!("drapekit: {}{n}", label());
}

/// `item ID: ` on a batch item's thread, else nothing.
fn label() -> String {
    ITEM.with(|item| match &*item.borrow() {
        Some(id) => format!("item {id}: "),
        None => String::new(),
    })
}
