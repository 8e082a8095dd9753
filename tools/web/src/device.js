// The device panel. Not built yet: it needs the device-session library.

export function devicePanel(el) {
  el.innerHTML = '<p class="muted">The device panel is not built yet.</p>';
}
