// The page talks to the server through the JSON API only (crates/server/API.md), so scripts can
// do everything the page does.

/** Calls the API; resolves to the parsed JSON (or text), rejects with the server's error text. */
export async function api(method, path, body) {
  const opts = { method, headers: {}, credentials: 'same-origin' };
  if (body !== undefined) {
    opts.headers['content-type'] = 'application/json';
    opts.body = JSON.stringify(body);
  }
  const r = await fetch(path, opts);
  const text = await r.text();
  let data = text;
  if ((r.headers.get('content-type') || '').includes('json')) {
    try { data = JSON.parse(text); } catch { /* keep the text */ }
  }
  if (!r.ok) {
    const e = new Error((data && data.error) || `${r.status} ${r.statusText}`);
    e.status = r.status;
    throw e;
  }
  return data;
}

/** Listens to /api/events; `handlers[type](data)` for each event type. Reconnects by itself. */
export function listen(handlers) {
  const es = new EventSource('/api/events');
  for (const [type, fn] of Object.entries(handlers)) {
    es.addEventListener(type, (ev) => fn(JSON.parse(ev.data)));
  }
  return es;
}
