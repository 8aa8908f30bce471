// A snapshot of the page (`?snapshot` in its address, docs/live_view.md): the live view draws
// the run as it is when the page opens and stops streaming, and the page's load event waits
// until it is drawn. `chromium --headless --screenshot URL` takes its picture at the load event:
// without the wait it would show an empty page at step 0, and a stream that never ends would
// keep a browser waiting for the network to go idle (--virtual-time-budget) forever.

/** True when the address asks for a snapshot. */
export function snapshotAsked() {
  return new URLSearchParams(location.search).has('snapshot');
}

/**
 * Holds the document's load event until the returned function is called. A script inserted
 * before the load event delays it until it has run; each one inserts the next when it has run,
 * so that one is always pending. They are data: URLs, which need no server.
 * @returns {() => void}
 */
export function holdLoad() {
  let held = true;
  const next = () => {
    if (!held) return;
    const script = document.createElement('script');
    script.src = 'data:text/javascript,';
    script.onload = script.onerror = () => {
      script.remove();
      next();
    };
    document.head.appendChild(script);
  };
  next();
  return () => {
    held = false;
  };
}
