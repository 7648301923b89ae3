// Shared helpers: API calls (with the optional bearer token), safe DOM building, number formatting.
export const API = "/api/v1";

export function token() { return localStorage.getItem("demcal-token") || ""; }

export class ApiError extends Error {
  constructor(status, detail) {
    const first = Array.isArray(detail) && detail.length ? detail[0] : { msg: String(detail), loc: [] };
    super(`${status}: ${first.msg}${first.loc && first.loc.length ? " (" + first.loc.join(".") + ")" : ""}`);
    this.status = status;
    this.detail = Array.isArray(detail) ? detail : [{ msg: String(detail), loc: [] }];
  }
}

export async function api(path, { method = "GET", body } = {}) {
  const headers = { Accept: "application/json" };
  if (body !== undefined) headers["Content-Type"] = "application/json";
  // every request: a server with tokens needs one for reads too (unless its operator opened them)
  if (token()) headers.Authorization = `Bearer ${token()}`;
  const response = await fetch(API + path, { method, headers, body: body === undefined ? undefined : JSON.stringify(body) });
  if (response.status === 204) return null;
  const data = await response.json().catch(() => ({ detail: [{ msg: response.statusText, loc: [] }] }));
  if (!response.ok) throw new ApiError(response.status, data.detail);
  return data;
}

// The OpenAPI document's component schemas (fetched once): forms read their fields' defaults and bounds there.
let schemaCache = null;
export async function schemas() {
  if (!schemaCache) schemaCache = (await api("/openapi.json")).components.schemas;
  return schemaCache;
}

// h("tag", {attr: value, onclick: fn}, child...) builds elements; strings become text nodes (never HTML).
export function h(tag, attrs = {}, ...children) {
  const el = document.createElement(tag);
  for (const [key, value] of Object.entries(attrs || {})) {
    if (value === undefined || value === null || value === false) continue;
    if (key.startsWith("on")) el.addEventListener(key.slice(2), value);
    else if (key === "className") el.className = value;
    else el.setAttribute(key, value === true ? "" : value);
  }
  for (const child of children.flat(Infinity)) {
    if (child === undefined || child === null || child === false) continue;
    el.append(child instanceof Node ? child : document.createTextNode(String(child)));
  }
  return el;
}

export function fmt(value, digits = 4) {
  if (value === null || value === undefined) return "–";
  if (typeof value !== "number") return String(value);
  if (!Number.isFinite(value)) return "–";
  if (value !== 0 && (Math.abs(value) >= 1e5 || Math.abs(value) < 1e-3)) return value.toExponential(digits - 1);
  return Number(value.toPrecision(digits)).toString();
}

// A wall time in the unit a person reads it in (the CLI's service/cli_resolution.py _duration says the same).
export function duration(seconds) {
  if (seconds < 120) return `${Math.round(seconds)} s`;
  return seconds < 7200 ? `${(seconds / 60).toFixed(1)} min` : `${(seconds / 3600).toFixed(1)} h`;
}

export function condition(cond) {
  const entries = Object.entries(cond || {});
  return entries.length ? entries.map(([k, v]) => `${k}=${fmt(v)}`).join(", ") : "–";
}

export function status(text) { return h("span", { className: `status ${text}` }, text); }

export function table(headers, rows) {
  return h("table", {}, h("thead", {}, h("tr", {}, headers.map((x) => h("th", {}, x)))),
    h("tbody", {}, rows.map((row) => h("tr", {}, row.map((cell) =>
      cell instanceof Node ? h("td", {}, cell) : h("td", { className: typeof cell === "number" ? "num" : "" }, fmt(cell)))))));
}

// Listings come a page at a time ({items, total, limit, offset}); the page's address keeps the offset
// (#/materials?offset=50), so a refresh or a shared link shows the same rows.
export const PAGE_SIZE = 50;

export function pageQuery(params, filters = {}, limit = PAGE_SIZE) {
  const offset = Math.max(0, parseInt(params.get("offset") || "0", 10) || 0);
  const query = new URLSearchParams({ ...filters, limit: String(limit), offset: String(offset) });
  for (const [key, value] of [...query]) if (value === "") query.delete(key);
  return query;
}

// "51–100 of 230" with Previous / Next links to the neighbouring pages of the same listing.
export function pager(page, params, route) {
  const link = (offset, text) => {
    const next = new URLSearchParams(params);
    if (offset > 0) next.set("offset", String(offset)); else next.delete("offset");
    return h("a", { href: `#${route}${next.size ? "?" + next : ""}`, className: "pager-link" }, text);
  };
  const first = page.items.length ? page.offset + 1 : page.offset;
  const last = page.offset + page.items.length;
  return h("p", { className: "pager muted" }, page.total ? `${first}–${last} of ${page.total}` : "none yet",
    page.offset > 0 ? [" · ", link(Math.max(0, page.offset - page.limit), "← previous")] : "",
    last < page.total ? [" · ", link(last, "next →")] : "");
}

export function flash(message, kind = "error") {
  const box = document.getElementById("flash");
  box.replaceChildren(message ? h("div", { className: kind }, message) : "");
}

export function formValues(form) {
  return Object.fromEntries(new FormData(form).entries());
}

// A 422's errors beside the fields they name. Each input that maps to an API field carries
// data-loc="factors.0.low" (the error's loc without "body"); an error is shown at the input whose
// data-loc is the longest prefix of its loc, or at the form's top when none matches (a rule across
// fields names them in its message). Returns how many were placed beside a field.
// The message goes inside the field's label, under its input: placed after the label (as before
// issue 31) it was the next item of the inline row and wrapped to the start of the next line, so
// friction_pp's error was drawn under particle_density_kg_m3. A row-level input (the row itself,
// e.g. low >= high) has no label: its message follows the row.
export function showFieldErrors(form, error) {
  clearFieldErrors(form);
  const fields = [...form.querySelectorAll("[data-loc]")];
  const general = [];
  let placed = 0;
  for (const item of error.detail || []) {
    const loc = (item.loc || []).filter((part) => part !== "body").map(String);
    let best = null, bestLen = 0;
    for (const field of fields) {
      const parts = field.dataset.loc.split(".");
      if (parts.length > bestLen && parts.length <= loc.length && parts.every((p, i) => p === loc[i])) { best = field; bestLen = parts.length; }
    }
    const text = item.msg.replace(/^Value error, /, "");
    if (best) {
      best.classList.add("invalid");
      best.setAttribute("aria-invalid", "true");
      const message = h("span", { className: "field-error", role: "alert" }, text);
      const label = best.closest("label");
      if (label && form.contains(label)) label.append(message); else best.after(message);
      placed += 1;
    } else {
      general.push(`${loc.join(".") || "request"}: ${text}`);
    }
  }
  const top = form.querySelector(".form-errors");
  if (top) top.replaceChildren(...general.map((msg) => h("div", { role: "alert" }, msg)));
  return placed;
}

export function clearFieldErrors(form) {
  form.querySelectorAll(".field-error").forEach((el) => el.remove());
  form.querySelectorAll(".invalid").forEach((el) => { el.classList.remove("invalid"); el.removeAttribute("aria-invalid"); });
  const top = form.querySelector(".form-errors");
  if (top) top.replaceChildren();
}

// Bring the first field in error (in the page's order) into view and give it the focus, so that
// a refusal is seen where it happened even when the button is far below it (the long campaign
// form); with no field to point at, the form's own error box. A row-level error focuses the
// row's first input.
export function revealFirstError(form) {
  const marked = form.querySelector(".invalid");
  const target = marked && !marked.matches("input, select, textarea, button")
    ? marked.querySelector("input, select, textarea") || marked : marked;
  const box = target || form.querySelector(".form-errors:not(:empty)");
  if (!box) return;
  box.scrollIntoView({ block: "center" });
  if (box === target) box.focus({ preventScroll: true });
}

// Submit a form's request; a 422 goes beside the fields (the first one brought into view),
// anything else to the flash line.
export async function submitForm(form, action) {
  clearFieldErrors(form);
  try {
    const result = await action();
    flash("");
    return result;
  } catch (error) {
    if (error instanceof ApiError && error.status === 422) {
      showFieldErrors(form, error);
      flash("Some fields need attention (marked below).", "error");
      revealFirstError(form);
    } else {
      flash(error.message, "error");
    }
    return undefined;
  }
}

// The first line of a stored error: the workers store one line, but older rows may hold a traceback,
// whose last line is the exception and its message.
export function oneLine(text) {
  const lines = String(text || "").split("\n").map((l) => l.trim()).filter(Boolean);
  if (!lines.length) return "";
  return lines[0].startsWith("Traceback") ? lines[lines.length - 1] : lines[0];
}

// Read an endpoint that answers 409 (not produced yet) or 404 (gone) as "nothing to show".
export async function optional(path) {
  try { return await api(path); } catch (error) { if (error.status === 409 || error.status === 404) return null; throw error; }
}

// A table in a box that scrolls sideways instead of overflowing its card (wide designs, many factors).
export function wideTable(headers, rows) {
  return h("div", { className: "scroll" }, table(headers, rows));
}

// Run an async action from a button or form, showing errors (with the field named) instead of failing silently.
export async function attempt(action, okMessage) {
  try {
    const result = await action();
    flash(okMessage || "", "ok");
    return result;
  } catch (error) {
    flash(error.message, "error");
    return undefined;
  }
}
