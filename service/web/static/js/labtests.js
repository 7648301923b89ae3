// The lab-test catalogue (GET /api/v1/tests, read from engine/lab/registry.py) for the job and campaign
// forms: the test select and one "include ..." checkbox per optional battery member, so the page lists
// exactly the tests the lab registers.
import { api, h } from "./core.js";

let catalogueCache = null;
export async function labTests() {
  if (!catalogueCache) catalogueCache = await api("/tests");
  return catalogueCache;
}

const titleOf = (catalogue, name) => (catalogue.tests.find((t) => t.name === name) || {}).title || "";

// The select of what a job (or each run of a campaign) simulates; the option's tooltip is the test's title.
export function testSelect(catalogue, loc) {
  return h("select", { name: "test", "data-loc": loc },
    catalogue.job_tests.map((name) => h("option", { value: name, title: titleOf(catalogue, name) }, name)));
}

// One checkbox per test a battery runs only when its switch is on; locOf(switch) is where the API
// reports an error of that option.
export function batteryChecks(catalogue, locOf) {
  return Object.entries(catalogue.battery.optional).map(([name, option]) => {
    const title = titleOf(catalogue, name);
    return h("label", { className: "check", title },
      h("input", { type: "checkbox", name: option, "data-loc": locOf(option) }), ` include ${title.split(":")[0].toLowerCase()}`);
  });
}

// The switches ticked in the form, as TestOptions entries.
export function batteryOptions(catalogue, data) {
  const options = {};
  for (const option of Object.values(catalogue.battery.optional)) if (data.get(option) === "on") options[option] = true;
  return options;
}
