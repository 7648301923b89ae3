// Hash router: #/jobs, #/jobs/7, #/submit, #/materials, #/materials/1, #/campaigns, #/campaigns/3, #/schedules.
import { flash, h } from "./core.js";
import { jobPage, jobsPage, submitPage } from "./jobs.js";
import { materialPage, materialsPage } from "./materials.js";
import { campaignPage, campaignsPage, schedulesPage } from "./campaigns.js";

const ROUTES = [
  [/^\/submit$/, (v) => submitPage(v)],
  [/^\/jobs$/, (v, _, q) => jobsPage(v, q)],
  [/^\/jobs\/(\d+)$/, (v, m) => jobPage(v, m[1])],
  [/^\/materials$/, (v) => materialsPage(v)],
  [/^\/materials\/(\d+)$/, (v, m) => materialPage(v, m[1])],
  [/^\/campaigns$/, (v, _, q) => campaignsPage(v, q)],
  [/^\/campaigns\/(\d+)$/, (v, m) => campaignPage(v, m[1])],
  [/^\/schedules$/, (v) => schedulesPage(v)],
];
const REFRESH_MS = 2000;
let timer = null;

async function render() {
  clearTimeout(timer);
  const [path, query] = (location.hash.slice(1) || "/jobs").split("?");
  const params = new URLSearchParams(query || "");
  const view = document.getElementById("view");
  const route = ROUTES.find(([re]) => re.test(path));
  if (!route) { view.replaceChildren(h("p", {}, `No page ${path}`)); return; }
  try {
    const live = await route[1](view, path.match(route[0]), params);
    // pages with queued or running work refresh themselves, unless the user is typing in a form
    if (live) timer = setTimeout(() => { if (!view.contains(document.activeElement) || document.activeElement === document.body) render(); else timer = setTimeout(render, REFRESH_MS); }, REFRESH_MS);
  } catch (error) {
    flash(error.message);
  }
}

const tokenInput = document.getElementById("token");
tokenInput.value = localStorage.getItem("demcal-token") || "";
tokenInput.addEventListener("change", () => localStorage.setItem("demcal-token", tokenInput.value));
window.addEventListener("hashchange", () => { flash(""); render(); });
render();
