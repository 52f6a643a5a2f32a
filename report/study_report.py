"""Outputs of a study run: result.json, report.md and the figures (generic ones here, the mechanism's own from its
problem's ``figures``)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from mechopt.errors import InputError
from mechopt.report.allowed_designs_section import allowed_designs_lines, allowed_designs_summary, variable_summary
from mechopt.report.convergence import plot_convergence
from mechopt.report.plots import plot_feasible_3d, plot_feasible_slices, plot_validation
from mechopt.report.tolerance_section import tolerance_lines, tolerance_summary
from mechopt.studies.reference_check import reference_warning

__all__ = ["write_outputs"]


def _figures(run) -> dict[str, str]:
    problem = run.study.problem
    stage = run.result.stages[0] if run.result.get("stages") else None  # only the sparse method has a line model
    fig_dir = run.out / "figures"
    marks = {name: run.study.design(name) for name in run.study.designs if name == "original"}
    marks["optimum"] = np.asarray(run.result.x)
    files: dict[str, Path] = {}
    designs = {k: v for k, v in run.study.reference_designs().items() if run.references[k]["status"] == "ok"}
    designs["optimum"] = np.asarray(run.result.x)
    files.update(problem.figures(designs, fig_dir))
    if run.result.get("history"):
        files["Progress: each simulation and the best so far"] = plot_convergence(
            run.result.history, fig_dir / "progress.png", label=problem.output_label(problem.objective),
            reference=None if run.truth is None else run.truth.fun, method=run.result.method)
    if problem.constraints:  # without constraints the region is the whole box, one flat colour
        files["Feasible region and each constraint's boundary"] = plot_feasible_slices(
            problem, fig_dir / "feasible_region.png", marks=marks, model=None if stage is None else stage.model)
    if problem.dim == 3 and stage is not None:
        ends = stage.model.from_u(stage.plan.segment_ends().reshape(-1, 3))
        files["Feasible region, sampling lines and their hull"] = plot_feasible_3d(
            problem, fig_dir / "feasible_3d.png", lines=stage.line_designs, hull_points=ends, marks=marks)
    if run.validation is not None and stage is not None:
        files["The model against its fitting lines and held-out lines"] = plot_validation(
            run.validation.lines, fig_dir / "validation.png", list(zip(stage.line_designs, stage.line_values,
                                                                        strict=True)),
            stage.model, label=problem.output_label(problem.objective), unit=_unit(problem))
    return {caption: str(Path(path).relative_to(run.out)) for caption, path in files.items()}


def _jsonable(value: Any) -> Any:
    if hasattr(value, "tolist"):
        return value.tolist()
    if isinstance(value, Path):
        return str(value)
    raise TypeError(f"{type(value).__name__} is not JSON-serializable")


def _design_table(r: dict[str, Any], problem, names: list[str], units: dict[str, str]) -> list[str]:
    """The designs' table: variables, outputs, savings against the original design (when the study has one) and the
    paper's own figures."""
    obj = problem.objective
    outputs = list(problem.outputs)
    papers = sorted({k for row in r["designs"] for k in row["paper"]})
    savings = any("savings_pct" in row for row in r["designs"])
    lines = ["| design | " + " | ".join(f"{n} ({units[n]})" if units[n] else n for n in names) + " | "
             + " | ".join(problem.output_label(k) for k in outputs) + (f" | {obj} savings" if savings else "")
             + " | " + "".join(f"{k} | " for k in papers) + "feasible |",
             "|---" * (len(names) + len(outputs) + len(papers) + 2 + savings) + "|"]
    for row in r["designs"]:
        values = [(_fmt(row["outputs"].get(k)) if row["status"] == "ok" else row["status"]) for k in outputs]
        saved = (f"{row['savings_pct']:.1f} %" if "savings_pct" in row else "—") + " | " if savings else ""
        lines.append(f"| {row['name']} | " + " | ".join(f"{row['design'][n]:.4f}" for n in names) + " | "
                     + " | ".join(values) + " | " + saved
                     + "".join(f"{_fmt(row['paper'].get(k))} | " for k in papers)
                     + f"{'yes' if row['feasible'] else 'no'} |")
    if papers:
        lines += ["", "The paper_* columns are the paper's own figures for the same designs (its model, not ours)"
                  + (": compare savings, not absolute values, where the models differ." if savings else ".")]
    return lines


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
        "problem": {"name": problem.name, "variables": [variable_summary(v) for v in problem.variables],
                    "objective": obj, "fit": problem.fit if res.model is None else res.model.fit,
                    "method": res.method, "fingerprint": problem.fingerprint(),
                    "settings": problem.settings()},
        "optimum": {"design": best["design"], "outputs": best["outputs"], "objective": res.fun,
                    "predicted": None if res.model is None else float(res.model.predict(np.asarray(res.x))[0]),
                    "margins": dict(zip(problem.constraints,
                                        problem.constraint_margins(np.asarray(res.x)[None, :])[0].tolist(),
                                        strict=True))},
        "designs": designs,
        "allowed_designs": allowed_designs_summary(problem, int(run.options.budget), run.references, float(res.fun)),
        "simulations": {**run.sampling, "model_lines": res.stages[0].n_samples if res.get("stages") else 0},
        "failures": [{"design": problem.design_dict(d), "error": e} for d, e in run.failures],
        "stages": [s.summary() for s in res.get("stages") or []],
        "history": [float(v) for v in res.get("history") or []],
        "message": res.message,
        "reference_warning": reference_warning(run.references, obj, float(res.fun), _unit(problem)),
        "trust": res.get("trust"),
        "validation": None if val is None else {
            "rmse": val.rmse, "rmse_low": val.rmse_low, "max_error": val.max_error, "f_min": val.f_min,
            "rmse_pct_of_f_min": val.rmse_pct, "rmse_pct_of_range": val.rmse_pct_of_range, "range": val.spread,
            "relative": val.relative_text(_unit(problem)), "n_points": val.n_points, "n_lines": len(val.lines),
            "unit": _unit(problem)},
        "ground_truth": None if run.truth is None else {
            "design": problem.design_dict(run.truth.x), "objective": run.truth.fun, "grid_step": run.truth.step,
            "gap_pct": 100 * (res.fun / run.truth.fun - 1) if run.truth.fun else None},
        "paper": study.paper,
        "reconstruction": (problem.reconstruction.summary()
                           if getattr(problem, "reconstruction", None) is not None else None),
        "options": run.options.to_dict(),
        "budget": int(run.options.budget),
        "plan": None if getattr(run, "plan", None) is None else run.plan.to_dict(),
        "store": str(run.store_path),
        "timings_s": run.timings,
        "tolerances": tolerance_summary(problem, res, study),
    }


def write_outputs(run) -> None:
    """Write the figures, result.json and report.md of a :class:`~mechopt.studies.runner.StudyRun`."""
    result = result_dict(run)
    result["figures"] = _figures(run)
    try:
        (run.out / "result.json").write_text(json.dumps(result, indent=2, default=_jsonable))
        (run.out / "report.md").write_text(report_markdown(result, run.study))
    except OSError as exc:
        raise InputError(f"cannot write the report into {run.out}: {exc.strerror or exc}") from None


def _unit(problem) -> str:
    """The objective's unit ("" when the problem does not declare it)."""
    return dict(problem.output_units).get(problem.objective, "")


def _fmt(value: Any) -> str:
    return f"{value:.4g}" if isinstance(value, int | float) and np.isfinite(value) else "—"


def _simulations_sentence(r: dict[str, Any]) -> str:
    """Where the run's simulations went: optimisation within the budget (by stage for the line model), validation
    on top of it (and by how much), references."""
    s, paper = r["simulations"], r["paper"] or {}
    budget = r.get("budget")
    within = f" (budget {budget})" if budget else ""
    if s["model_lines"]:
        spent = (f"Simulations: {s['optimisation']} to optimise{within}: {s['model_lines']} on the lines of the "
                 "global model"
                 + (f" (paper: {paper['fit_simulations']})" if "fit_simulations" in paper else "")
                 + f", {s['optimisation'] - s['model_lines']} more to confirm and refine its candidate")
    else:
        spent = f"Simulations: {s['optimisation']} by the method {r['problem']['method']}{within}"
    share = f", {s['validation'] / budget:.0%} of it" if budget and s["validation"] else ""
    validation = (f"; {s['validation']} held-out ones to validate the model, on top of the budget{share}"
                  if s["validation"] else "; no held-out validation")
    return (spent + validation
            + (f" (paper: {paper['validation_simulations']})" if "validation_simulations" in paper else "")
            + f"; {s['references']} more for the reference designs. Of these, {s['new']} were simulated by this run, "
            f"{s['reused']} reused from the store, {s['waited_for_other_runs']} computed by another run on the same "
            f"store, and {s['failed']} failed. Executor: {s['executor']}.")


def _validation_paragraph(v: dict[str, Any], obj: str, paper: dict[str, Any]) -> list[str]:
    """The held-out errors, absolute in the objective's unit and relative to the held-out values' range."""
    unit = f" {v['unit']}" if v.get("unit") else ""
    text = (f"{v['n_points']} held-out simulations on {v['n_lines']} lines in other directions than the model's own, "
            f"inside its hull: RMSE {v['rmse']:.4g}{unit} ({v['relative']}), {_fmt(v['rmse_low'])}{unit} where {obj} "
            f"<= 2 × the best simulated value, largest error {v['max_error']:.4g}{unit}")
    if "validation_rmse" in paper:
        text += f". The paper: RMSE {paper['validation_rmse']}"
        if "validation_rmse_low" in paper:
            text += f", {paper['validation_rmse_low']} below {paper.get('validation_rmse_low_below')}"
    return ["", "## Validation", "", text + "."]


def _plan_section(r: dict[str, Any]) -> list[str]:
    """The plan printed before the run, beside what the run took."""
    plan = r.get("plan")
    if not plan:
        return []
    per_run = plan["seconds_per_run"]
    lines = ["", "## Plan and cost", "",
             f"Before its first simulation the run planned (on {plan['workers']} workers; "
             + (f"{per_run:.3g} s a simulation, {plan['cost_source'].split(': ', 1)[-1]}" if per_run is not None
                else "the time of a simulation unknown") + "):", "",
             "| stage | simulations | already in the store |", "|---|---|---|"]
    lines += [f"| {st['name']} | {'' if st['exact'] else 'up to '}{st['simulations']} | {st['held']} |"
              for st in plan["stages"]]
    expected = "" if plan["expected_s"] is None else f"; the plan expected about {plan['expected_s']:.0f} s"
    lines += ["", f"At most {plan['total']} designs, {plan['new']} to simulate{expected}. The run took "
              f"{r['timings_s'].get('total_s', float('nan')):.1f} s in all."]
    return lines


def report_markdown(r: dict[str, Any], study) -> str:
    """The human summary (``report.md``) of a :func:`result_dict`."""
    problem = study.problem
    obj = r["problem"]["objective"]
    names = [v["name"] for v in r["problem"]["variables"]]
    units = {v["name"]: v["unit"] for v in r["problem"]["variables"]}
    o = r["optimum"]
    paper = r["paper"] or {}
    lines = [f"# Study `{r['study']}`", "", study.description, "",
             f"**Optimum**: {problem.describe(np.array([o['design'][n] for n in names]))} — "
             f"{problem.output_label(obj)} {o['objective']:.6g}"
             + ("" if o["predicted"] is None else f" (model {o['predicted']:.6g})") + ".", "",
             _simulations_sentence(r), "",
             *([f"**W{r['reference_warning'][1:]}**", ""] if r.get("reference_warning") else []),
             "## Designs", ""]
    lines += _design_table(r, problem, names, units)
    lines += allowed_designs_lines(r)
    lines += tolerance_lines(r)
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
    if r["validation"]:
        lines += _validation_paragraph(r["validation"], obj, paper)
    lines += _plan_section(r)
    if r["stages"]:  # the line model's stages (the sparse method)
        lines += ["", "## Stages", "", f"| stage | lines | samples | coverage | model {obj} | simulated {obj} |",
                  "|---|---|---|---|---|---|"]
        lines += [f"| {st['name']} | {st['n_lines']} | {st['n_samples']} | {st['coverage']:.0%} | "
                  f"{st['predicted']:.6g} | {st['simulated']:.6g} |" for st in r["stages"]]
    else:
        lines += ["", "## The run"]
    lines += ["", r["message"], "", "## Timings", "", "| step | seconds |", "|---|---|"]
    lines += [f"| {k.removesuffix('_s')} | {t:.2f} |" for k, t in r["timings_s"].items()]
    lines += ["", "## Figures", ""]
    for caption, rel in r.get("figures", {}).items():
        lines += [f"### {caption}", "", f"![{caption}]({rel})", ""]
    return "\n".join(lines)
