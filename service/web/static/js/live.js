// Live updates: every action re-renders the current view through refresh(), and a view that has
// queued or running work asks to be re-rendered again shortly. Why a module of its own: the pages
// cannot import the router (it imports them); the router registers its render function here.
// (Before this, buttons re-drew their page once and never scheduled the next refresh, so a
// campaign stayed "running, iteration 0" after Start.)
const REFRESH_MS = 1500;
let renderer = null;
let timer = null;

export function setRenderer(render) { renderer = render; }

// Re-render now (after an action), cancelling any pending refresh.
export function refresh() {
  clearTimeout(timer);
  timer = null;
  if (renderer) return renderer();
  return undefined;
}

// Called by the router after each render: keep refreshing while the view says something runs,
// but never while the user is typing in one of its forms (their input would be wiped).
export function schedule(live) {
  clearTimeout(timer);
  timer = null;
  if (!live) return;
  timer = setTimeout(function tick() {
    const view = document.getElementById("view");
    const typing = view.contains(document.activeElement) && document.activeElement.closest("form");
    if (typing) timer = setTimeout(tick, REFRESH_MS);
    else refresh();
  }, REFRESH_MS);
}
