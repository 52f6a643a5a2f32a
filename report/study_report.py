"""Outputs of a study run: result.json, report.md and the figures (generic ones here, the mechanism's own from its
problem's ``figures``)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from mechopt.errors import InputError
from mechopt.report.plots import plot_feasible_3d, plot_feasible_slices, plot_validation

__all__ = ["write_outputs"]


def _figures(run) -> dict[str, str]:
    problem, stage = run.study.problem, run.result.stages[0]
    fig_dir = run.out / "figures"
    marks = {name: run.study.design(name) for name in run.study.designs if name == "original"}
    marks["optimum"] = np.asarray(run.result.x)
    files: dict[str, Path] = {}
    designs = {k: v for k, v in run.study.reference_designs().items() if run.references[k]["status"] == "ok"}
    designs["optimum"] = np.asarray(run.result.x)
    files.update(problem.figures(designs, fig_dir))
    files["Feasible region and each constraint's boundary"] = plot_feasible_slices(
        problem, fig_dir / "feasible_region.png", marks=marks, model=stage.model)
    if problem.dim == 3:
        ends = stage.model.from_u(stage.plan.segment_ends().reshape(-1, 3))
        files["Feasible region, sampling lines and their hull"] = plot_feasible_3d(
            problem, fig_dir / "feasible_3d.png", lines=stage.line_designs, hull_points=ends, marks=marks)
    if run.validation is not None:
        files["The model against its fitting lines and held-out lines"] = plot_validation(
            run.validation.lines, fig_dir / "validation.png", list(zip(stage.line_designs, stage.line_values,
                                                                        strict=True)),
            stage.model, label=f"{problem.objective}")
    return {caption: str(Path(path).relative_to(run.out)) for caption, path in files.items()}


def _jsonable(value: Any) -> Any:
    if hasattr(value, "tolist"):
        return value.tolist()
    if isinstance(value, Path):
        return str(value)
    raise TypeError(f"{type(value).__name__} is not JSON-serializable")


def result_dict(run) -> dict[str, Any]:
    """The machine-readable summary of a run (``result.json``)."""
    study, res, problem = run.study, run.result, run.study.problem
    best = run.references["optimum"]
    val = run.validation
    orig = run.references.get("original")
    obj = problem.objective
    designs = []
    for name, ref in run.references.items():
        row = {"name": name, **ref, "paper": {k: v for k, v in study.designs.get(name, {}).items()
                                              if k.startswith("paper_")}}
        if orig is not None and orig["status"] == ref["status"] == "ok" and orig["outputs"].get(obj):
            row["savings_pct"] = 100 * (1 - ref["outputs"][obj] / orig["outputs"][obj])
        designs.append(row)
    return {
        "study": study.name,
        "kind": study.kind,
        "problem": {"name": problem.name, "variables": [{"name": v.name, "unit": v.unit, "lower": v.lower,
                                                         "upper": v.upper} for v in problem.variables],
                    "objective": obj, "fit": res.model.fit, "fingerprint": problem.fingerprint(),
                    "settings": problem.settings()},
        "optimum": {"design": best["design"], "outputs": best["outputs"], "objective": res.fun,
                    "predicted": float(res.model.predict(np.asarray(res.x))[0]),
                    "margins": dict(zip(problem.constraints,
                                        problem.constraint_margins(np.asarray(res.x)[None, :])[0].tolist(),
                                        strict=True))},
        "designs": designs,
        "simulations": {**run.sampling, "model_lines": res.stages[0].n_samples},
        "failures": [{"design": problem.design_dict(d), "error": e} for d, e in run.failures],
        "stages": [s.summary() for s in res.stages],
        "message": res.message,
        "trust": res.get("trust"),
        "validation": None if val is None else {
            "rmse": val.rmse, "rmse_low": val.rmse_low, "max_error": val.max_error, "f_min": val.f_min,
            "rmse_pct_of_f_min": val.rmse_pct, "rmse_pct_of_range": val.rmse_pct_of_range, "range": val.spread,
            "relative": val.relative_text(), "n_points": val.n_points, "n_lines": len(val.lines)},
        "ground_truth": None if run.truth is None else {
            "design": problem.design_dict(run.truth.x), "objective": run.truth.fun, "grid_step": run.truth.step,
            "gap_pct": 100 * (res.fun / run.truth.fun - 1) if run.truth.fun else None},
        "paper": study.paper,
        "reconstruction": (problem.reconstruction.summary()
                           if getattr(problem, "reconstruction", None) is not None else None),
        "options": run.options.to_dict(),
        "store": str(run.store_path),
        "timings_s": run.timings,
    }


def write_outputs(run) -> None:
    """Write the figures, result.json and report.md of a :class:`~mechopt.cli.run_study.StudyRun`."""
    result = result_dict(run)
    result["figures"] = _figures(run)
    try:
        (run.out / "result.json").write_text(json.dumps(result, indent=2, default=_jsonable))
        (run.out / "report.md").write_text(report_markdown(result, run.study))
    except OSError as exc:
        raise InputError(f"cannot write the report into {run.out}: {exc.strerror or exc}") from None


def _fmt(value: Any) -> str:
    return f"{value:.4g}" if isinstance(value, int | float) and np.isfinite(value) else "—"


def report_markdown(r: dict[str, Any], study) -> str:
    """The human summary (``report.md``) of a :func:`result_dict`."""
    problem = study.problem
    obj = r["problem"]["objective"]
    names = [v["name"] for v in r["problem"]["variables"]]
    units = {v["name"]: v["unit"] for v in r["problem"]["variables"]}
    o = r["optimum"]
    s = r["simulations"]
    paper = r["paper"] or {}
    lines = [f"# Study `{r['study']}`", "", study.description, "",
             f"**Optimum**: {problem.describe(np.array([o['design'][n] for n in names]))} — "
             f"{problem.output_label(obj)} {o['objective']:.6g} (model {o['predicted']:.6g}).", "",
             f"Simulations: {s['model_lines']} on the lines of the global model"
             + (f" (paper: {paper['fit_simulations']})" if "fit_simulations" in paper else "")
             + f", {s['optimisation'] - s['model_lines']} more to confirm and refine its candidate, {s['validation']} "
             f"held-out ones to validate"
             + (f" (paper: {paper['validation_simulations']})" if "validation_simulations" in paper else "")
             + f", {s['references']} for the reference designs. Of these, {s['new']} were simulated by this run, "
             f"{s['reused']} reused from the store, {s['waited_for_other_runs']} computed by another run on the same "
             f"store, and {s['failed']} failed. Executor: {s['executor']}.", "",
             "## Designs", ""]
    outputs = list(problem.outputs)
    papers = sorted({k for row in r["designs"] for k in row["paper"]})
    lines += ["| design | " + " | ".join(f"{n} ({units[n]})" if units[n] else n for n in names) + " | "
              + " | ".join(problem.output_label(k) for k in outputs) + f" | {obj} savings | "
              + "".join(f"{k} | " for k in papers) + "feasible |",
              "|---" * (len(names) + len(outputs) + len(papers) + 3) + "|"]
    for row in r["designs"]:
        values = [(_fmt(row["outputs"].get(k)) if row["status"] == "ok" else row["status"]) for k in outputs]
        lines.append(f"| {row['name']} | " + " | ".join(f"{row['design'][n]:.4f}" for n in names) + " | "
                     + " | ".join(values) + " | "
                     + (f"{row['savings_pct']:.1f} %" if "savings_pct" in row else "—") + " | "
                     + "".join(f"{_fmt(row['paper'].get(k))} | " for k in papers)
                     + f"{'yes' if row['feasible'] else 'no'} |")
    if papers:
        lines += ["", "The paper_* columns are the paper's own figures for the same designs (its model, not ours): "
                  "compare savings, not absolute values, where the models differ."]
    if r["failures"]:
        lines += ["", f"## Failed simulations ({len(r['failures'])})", "", "| design | error |", "|---|---|"]
        lines += [f"| {problem.describe(np.array([f['design'][n] for n in names]))} | {f['error']} |"
                  for f in r["failures"][:50]]
    g = r["ground_truth"]
    if g:
        lines += ["", "## Against the ground truth", "",
                  f"A brute force of the batch evaluator over the whole region (grid {g['grid_step']:g}, then a "
                  f"constrained polish) finds {problem.describe(np.array([g['design'][n] for n in names]))} with "
                  f"{obj} {g['objective']:.6g}; the optimum found here is {g['gap_pct']:+.3f} % from it."]
    if r.get("trust"):
        lines += ["", f"**Trust**: {r['trust']['verdict']}."]
    v = r["validation"]
    if v:
        lines += ["", "## Validation", "",
                  f"{v['n_points']} held-out simulations on {v['n_lines']} lines in other directions than the model's "
                  f"own, inside its hull: RMSE {v['rmse']:.4g} ({v['relative']}), {_fmt(v['rmse_low'])} where {obj} "
                  f"<= 2 × the best simulated value, max error {v['max_error']:.4g}."
                  + (f" The paper: RMSE {paper['validation_rmse']}" if "validation_rmse" in paper else "")
                  + (f", {paper['validation_rmse_low']} below {paper.get('validation_rmse_low_below')}"
                     if "validation_rmse_low" in paper else "") + "."]
    lines += ["", "## Stages", "", f"| stage | lines | samples | coverage | model {obj} | simulated {obj} |",
              "|---|---|---|---|---|---|"]
    for st in r["stages"]:
        lines.append(f"| {st['name']} | {st['n_lines']} | {st['n_samples']} | {st['coverage']:.0%} | "
                     f"{st['predicted']:.6g} | {st['simulated']:.6g} |")
    lines += ["", r["message"], "", "## Timings", "", "| step | seconds |", "|---|---|"]
    lines += [f"| {k.removesuffix('_s')} | {t:.2f} |" for k, t in r["timings_s"].items()]
    lines += ["", "## Figures", ""]
    for caption, rel in r.get("figures", {}).items():
        lines += [f"### {caption}", "", f"![{caption}]({rel})", ""]
    return "\n".join(lines)
