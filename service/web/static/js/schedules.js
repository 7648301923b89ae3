// Schedules: recurring campaigns (created from a campaign's page), enable/disable/delete.
import { api, attempt, h, pageQuery, pager, table } from "./core.js";
import { refresh } from "./live.js";

export async function schedulesPage(view, params = new URLSearchParams()) {
  const page = await api(`/schedules?${pageQuery(params)}`);
  const schedules = page.items;
  view.replaceChildren(h("h2", {}, `Schedules (${page.total})`),
    h("p", { className: "muted" }, "Missed runs coalesce: after downtime, at most one catch-up campaign starts. Create a schedule from a campaign's page."),
    table(["Id", "Name", "Cron (UTC)", "Enabled", "Only new data", "Next run", "Last campaign", "Owner", ""],
      schedules.map((s) => [String(s.id), s.name, s.cron, s.enabled ? "yes" : "no", s.only_if_new_measurements ? "yes" : "no",
        s.next_run_at, s.last_campaign_id ? h("a", { href: `#/campaigns/${s.last_campaign_id}` }, `#${s.last_campaign_id}`) : "–",
        s.owner || "–",
        h("span", {},
          h("button", { className: "secondary", onclick: async () => {
            if (await attempt(() => api(`/schedules/${s.id}`, { method: "PATCH", body: { enabled: !s.enabled } }))) refresh();
          } }, s.enabled ? "Disable" : "Enable"), " ",
          h("button", { className: "secondary", onclick: async () => {
            if (await attempt(() => api(`/schedules/${s.id}`, { method: "DELETE" }), "deleted")) refresh();
          } }, "Delete"))])), pager(page, params, "/schedules"));
  return false;
}
