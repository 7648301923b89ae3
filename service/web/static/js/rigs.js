// Rigs: the apparatus measurements are made in (GET /api/v1/rigs), listed and read; SI values shown in mm.
import { api, fmt, h, pageQuery, pager, table } from "./core.js";

const SECTIONS = ["shear_box", "fill", "angle_of_repose", "anchor"];

function box(r) {
  const b = r.shear_box;
  return b ? `${fmt(1000 * b.container_diameter_m)} mm across, halves ${fmt(1000 * b.bottom_half_height_m)}/${fmt(1000 * b.top_half_height_m)} mm, gap ${fmt(1000 * b.gap_m)} mm` : "–";
}

export async function rigsPage(view, params = new URLSearchParams()) {
  const page = await api(`/rigs?${pageQuery(params)}`);
  const rigs = page.items;
  view.replaceChildren(h("h2", {}, "Rigs"),
    h("p", { className: "muted" }, "The apparatus measurements are made in. Create one with POST /api/v1/rigs or `demcal rig create FILE`."),
    table(["Id", "Name", "Shear box", "Sections", "Bundled"],
      rigs.map((r) => [String(r.id), h("a", { href: `#/rigs/${r.id}` }, r.name), box(r),
        SECTIONS.filter((s) => r[s]).join(", "), r.bundled ? "yes (read-only)" : "no"])),
    pager(page, params, "/rigs"));
}

export async function rigPage(view, id) {
  const r = await api(`/rigs/${id}`);
  const value = (v) => (Array.isArray(v) ? v.map((x) => fmt(x)).join(", ") : typeof v === "boolean" ? (v ? "yes" : "no") : fmt(v));
  view.replaceChildren(h("h2", {}, r.name), h("p", { className: "muted" }, r.description || ""),
    h("p", { className: "muted" }, r.source || ""),
    ...SECTIONS.filter((s) => r[s]).flatMap((s) => [h("h3", {}, s.replaceAll("_", " ")),
      table(["Field (SI)", "Value"], Object.entries(r[s]).map(([k, v]) => [k, value(v)]))]),
    r.bundled ? h("p", { className: "muted" }, "Bundled record, read-only.") : "");
}
