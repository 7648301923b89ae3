// Hash router: #/jobs, #/jobs/7, #/submit, #/materials, #/materials/1, #/campaigns, #/campaigns/3[?iteration=2],
// #/schedules, #/rigs, #/rigs/2. Unknown pages and missing rows get a not-found page (never the previous page's content).
import { flash, h } from "./core.js";
import { jobPage, jobsPage, submitPage } from "./jobs.js";
import { materialPage, materialsPage } from "./materials.js";
import { rigPage, rigsPage } from "./rigs.js";
import { campaignsPage } from "./campaigns.js";
import { campaignPage } from "./campaign.js";
import { schedulesPage } from "./schedules.js";
import { schedule, setRenderer } from "./live.js";
import { sweepCharts } from "./plot.js";

const ROUTES = [
  [/^\/submit$/, (v) => submitPage(v)],
  [/^\/jobs$/, (v, _, q) => jobsPage(v, q)],
  [/^\/jobs\/(\d+)$/, (v, m) => jobPage(v, m[1])],
  [/^\/materials$/, (v, _, q) => materialsPage(v, q)],
  [/^\/materials\/(\d+)$/, (v, m) => materialPage(v, m[1])],
  [/^\/rigs$/, (v, _, q) => rigsPage(v, q)],
  [/^\/rigs\/(\d+)$/, (v, m) => rigPage(v, m[1])],
  [/^\/campaigns$/, (v, _, q) => campaignsPage(v, q)],
  [/^\/campaigns\/(\d+)$/, (v, m, q) => campaignPage(v, m[1], q)],
  [/^\/schedules$/, (v, _, q) => schedulesPage(v, q)],
];

function notFound(view, what) {
  sweepCharts();
  document.title = "Not found · demcal";
  view.replaceChildren(h("section", { className: "card not-found" }, h("h2", {}, "Not found"),
    h("p", {}, what), h("p", {}, h("a", { href: "#/jobs" }, "Jobs"), " · ", h("a", { href: "#/campaigns" }, "Campaigns"),
      " · ", h("a", { href: "#/materials" }, "Materials"))));
}

let rendering = 0;
async function render() {
  const ticket = ++rendering;
  const [path, query] = (location.hash.slice(1) || "/jobs").split("?");
  const params = new URLSearchParams(query || "");
  const view = document.getElementById("view");
  const route = ROUTES.find(([re]) => re.test(path));
  if (!route) { schedule(false); notFound(view, `There is no page ${path}.`); return; }
  try {
    // the page is built off-screen and swapped in whole, so a slow answer for an old page can
    // never overwrite a newer one (navigation or an action's refresh)
    const fresh = h("div");
    const live = await route[1](fresh, path.match(route[0]), params);
    if (ticket !== rendering) return;
    document.title = `${fresh.querySelector("h2")?.textContent || "demcal"} · demcal`;
    view.replaceChildren(...fresh.childNodes);
    sweepCharts();
    schedule(live);
  } catch (error) {
    if (ticket !== rendering) return;
    schedule(false);
    if (error.status === 404) notFound(view, error.detail?.[0]?.msg || `There is no page ${path}.`);
    else {
      // 401: the server has tokens and this browser sent none (or a wrong one): say where it goes
      const hint = error.status === 401 ? h("p", {}, "This server needs a token: enter yours in the Token field above.") : "";
      view.replaceChildren(h("section", { className: "card" }, h("h2", {}, "This page could not be shown"), h("p", { className: "bad" }, error.message), hint)); flash("");
    }
  }
}

setRenderer(render);
const tokenInput = document.getElementById("token");
tokenInput.value = localStorage.getItem("demcal-token") || "";
tokenInput.addEventListener("change", () => { localStorage.setItem("demcal-token", tokenInput.value); render(); });
window.addEventListener("hashchange", () => { flash(""); render(); });
render();
