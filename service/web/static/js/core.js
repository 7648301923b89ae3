// Shared helpers: API calls (with the optional bearer token), safe DOM building, number formatting.
export const API = "/api/v1";

export function token() { return localStorage.getItem("demcal-token") || ""; }

export class ApiError extends Error {
  constructor(status, detail) {
    const first = Array.isArray(detail) && detail.length ? detail[0] : { msg: String(detail), loc: [] };
    super(`${status}: ${first.msg}${first.loc && first.loc.length ? " (" + first.loc.join(".") + ")" : ""}`);
    this.status = status; this.detail = detail;
  }
}

export async function api(path, { method = "GET", body } = {}) {
  const headers = { Accept: "application/json" };
  if (body !== undefined) headers["Content-Type"] = "application/json";
  if (method !== "GET" && token()) headers.Authorization = `Bearer ${token()}`;
  const response = await fetch(API + path, { method, headers, body: body === undefined ? undefined : JSON.stringify(body) });
  if (response.status === 204) return null;
  const data = await response.json().catch(() => ({ detail: [{ msg: response.statusText, loc: [] }] }));
  if (!response.ok) throw new ApiError(response.status, data.detail);
  return data;
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

export function flash(message, kind = "error") {
  const box = document.getElementById("flash");
  box.replaceChildren(message ? h("div", { className: kind }, message) : "");
}

export function formValues(form) {
  return Object.fromEntries(new FormData(form).entries());
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
