//! The page's status lines: plain text in elements of `index.html`, found by id. In the worker
//! (no document) these do nothing.

use terrain::controls::{self, Action};

/// The element with id `id`, if the page has it.
fn element(id: &str) -> Option<web_sys::Element> {
    web_sys::window()?.document()?.get_element_by_id(id)
}

/// Sets the text of the element `id`.
pub(super) fn set_text(id: &str, text: &str) {
    if let Some(element) = element(id) {
        element.set_text_content(Some(text));
    }
}

/// Shows `message` in the page's error box (and in the console), and hides the progress line.
pub(super) fn show_error(message: &str) {
    web_sys::console::error_1(&message.into());
    if let Some(element) = element("error") {
        element.set_text_content(Some(message));
        let _ = element.remove_attribute("hidden");
    }
    if let Some(progress) = element("progress") {
        let _ = progress.set_attribute("hidden", "");
    }
}

/// Whether the canvas still holds the pointer lock (the browser releases it on Esc without
/// telling the page's keys).
pub(super) fn pointer_locked() -> bool {
    web_sys::window()
        .and_then(|window| window.document())
        .and_then(|document| document.pointer_lock_element())
        .is_some()
}

/// The page's saved settings (the tuning panel's Save), if any.
pub(super) fn stored(key: &str) -> Option<String> {
    web_sys::window()?.local_storage().ok()??.get_item(key).ok()?
}

/// Saves `value` under `key` in the browser's storage for this site.
pub(super) fn store(key: &str, value: &str) -> Result<(), String> {
    let storage = web_sys::window()
        .and_then(|window| window.local_storage().ok().flatten())
        .ok_or("this browser gives the page no storage")?;
    storage
        .set_item(key, value)
        .map_err(|_| "the browser refused to store the settings (storage full?)".to_string())
}

/// Fills the page's list `#controls` from the window's key table ([`controls::BINDINGS`]), with
/// what each key does in a page (Esc frees the mouse; screenshots are the browser's).
pub(super) fn list_controls() {
    let Some(document) = web_sys::window().and_then(|window| window.document()) else { return };
    let Some(list) = document.get_element_by_id("controls") else { return };
    for binding in controls::BINDINGS {
        let effect = match binding.action {
            Action::Quit => "free the mouse",
            Action::Screenshot => continue,
            _ => binding.effect,
        };
        if let Ok(item) = document.create_element("li") {
            item.set_text_content(Some(&format!("{}: {effect}", binding.names)));
            let _ = list.append_child(&item);
        }
    }
}
