"""``demcal job ...``: submit, follow, cancel and retry DEM and stand-in jobs through the HTTP API.

The same calls as POST/GET /api/v1/jobs..., so a script can do what the web page and curl do;
errors are one line on stderr and exit status 2 (service.cli_http).
"""
from __future__ import annotations

from calibration.evaluator_registry import names as evaluator_names
from engine.lab.registry import job_test_names
from service.cli_http import (CliError, call, emit, fmt, leaf, page_footer, page_options, page_params, pairs, read_json,
                              table, watch, watch_options)
from service.cli_resolution import estimate_line, resolution_body, resolution_options
from service.vocabulary import JobStatus


def _status_line(j: dict) -> str:
    progress = j.get("progress") or {}
    text = (f"job {j['id']}: {j['status']} ({j['test']}, {j['fidelity']}, seed {j['seed']}, {j['evaluator']}), "
            f"{100.0 * float(progress.get('fraction') or 0.0):.0f} % {progress.get('phase') or ''}".rstrip())
    return text + (f"\nerror: {j['error']}" if j.get("error") else "")


def job_submit(args) -> int:
    body = read_json(args.file) if args.file else {}
    for key in ("test", "fidelity", "seed", "evaluator", "priority"):
        value = getattr(args, key)
        if value is not None:
            body[key] = value
    if args.param:
        body.setdefault("parameters", {}).update(pairs(args.param, "--param"))
    if args.idempotency_key:
        body["idempotency_key"] = args.idempotency_key
    resolution = resolution_body(args)
    if resolution is not None:
        body["resolution"] = resolution
    j = call(args, "POST", "/jobs", body)
    estimate = estimate_line(j.get("estimate"))
    return emit(args, j, _status_line(j) + (f"\n{estimate.replace('each battery', 'cost')}" if estimate else ""))


def job_list(args) -> int:
    params = page_params(args, status=args.status, test=args.test, campaign_id=args.campaign)
    data = call(args, "GET", "/jobs", params=params)
    jobs = data["items"]
    rows = [[j["id"], j["status"], j["test"], j["fidelity"], j["seed"], j["evaluator"],
             f"{100.0 * float((j.get('progress') or {}).get('fraction') or 0.0):.0f} %", j.get("campaign_id")]
            for j in jobs]
    return emit(args, data, table(["id", "status", "test", "fidelity", "seed", "evaluator", "progress", "campaign"],
                                  rows) + page_footer(data))


def job_status(args) -> int:
    """A job's state; --watch follows it until it finishes (exit status 0 when it succeeded, else 1)."""
    def fetch() -> dict:
        return call(args, "GET", f"/jobs/{args.id}")

    if not args.watch:
        j = fetch()
        return emit(args, j, _status_line(j))
    if args.json:
        raise CliError("--watch draws progress for people; poll without it for --json")
    j = watch(args, fetch, _status_line, lambda j: j["status"] in JobStatus.finished())
    return 0 if j["status"] == JobStatus.SUCCEEDED else 1


def job_result(args) -> int:
    from calibration.keys import responses_of

    r = call(args, "GET", f"/jobs/{args.id}/result", params={"include_curves": "false"})
    rows = [[x["test"], x["quantity"], fmt(x["condition"]), x["value"], x["unit"]]
            for x in responses_of(r).values()]
    return emit(args, r, table(["test", "quantity", "condition", "value", "unit"], rows))


def job_action(args) -> int:
    j = call(args, "POST", f"/jobs/{args.id}/{args.action}")
    return emit(args, j, _status_line(j))


def register(subparsers) -> None:
    job = subparsers.add_parser("job", help="queued DEM and stand-in jobs")
    jsub = job.add_subparsers(dest="job_command", required=True)
    submit = leaf(jsub, "submit", job_submit, "queue a job from a JSON body (as POST /jobs) and/or flags",
                  creates=True)
    submit.add_argument("--file", help="JSON body, '-' for stdin")
    submit.add_argument("--test", choices=job_test_names())
    submit.add_argument("--fidelity", choices=["screening", "thesis"])
    resolution_options(submit)
    submit.add_argument("--seed", type=int)
    submit.add_argument("--evaluator", choices=evaluator_names())
    submit.add_argument("--priority", type=int)
    submit.add_argument("--param", action="append", help="NAME=VALUE micro parameter in SI, e.g. friction_pp=0.6")
    submit.add_argument("--idempotency-key", help="submitting twice with one key queues one job")
    lst = leaf(jsub, "list", job_list, "list jobs, newest first")
    lst.add_argument("--status", choices=JobStatus.values())
    lst.add_argument("--test", choices=job_test_names())
    lst.add_argument("--campaign", type=int, help="only this campaign's jobs")
    page_options(lst)
    status = leaf(jsub, "status", job_status, "a job's state and progress")
    status.add_argument("id", type=int)
    watch_options(status, "it finishes (exit status 0 when it succeeded, else 1)")
    leaf(jsub, "result", job_result, "a finished job's bulk values (SI)").add_argument("id", type=int)
    for action, text in (("cancel", "cancel a queued job, or ask a running one to stop"),
                         ("retry", "queue a failed or cancelled job again")):
        leaf(jsub, action, job_action, text).add_argument("id", type=int)
        jsub.choices[action].set_defaults(action=action)


__all__ = ["register", "CliError"]
