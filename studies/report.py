"""Outputs of a study run: result.json, report.md and the figures."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .design_space import from_u
from .plots import (
    animate_cycle,
    plot_feasible_3d,
    plot_feasible_slices,
    plot_mechanisms,
    plot_torque_comparison,
    plot_validation,
)


def _figures(run, fig_dir: Path) -> dict[str, str]:
    study, pipeline = run.study, run.pipeline
    best = run.references["optimum (mechopt)"]
    marks = {"original": study.design("original")} if "original" in study.designs else {}
    marks["optimum"] = best.design
    global_stage = pipeline.stages[0]
    files = {}
    files["torque"] = plot_torque_comparison(
        {k: v for k, v in run.references.items() if k in ("original", "paper_global_optimum", "optimum (mechopt)")},
        fig_dir / "torque_comparison.png")
    mech = {"original": study.design("original")} if "original" in study.designs else {}
    mech["optimum (mechopt)"] = best.design
    files["mechanisms"] = plot_mechanisms(mech, study, fig_dir / "mechanisms.png")
    files["animation"] = animate_cycle(best, study, fig_dir / "optimum_cycle.gif")
    oa = sorted({float(study.region[0, 0]), float(best.design[0]), float(np.mean(study.region[0])),
                 float(study.region[0, 1])})
    files["slices"] = plot_feasible_slices(study, fig_dir / "feasible_slices.png", oa_values=oa, marks=marks)
    ends = from_u(global_stage.plan.segment_ends().reshape(-1, 3))
    files["region_3d"] = plot_feasible_3d(study, fig_dir / "feasible_3d.png", lines=global_stage.line_designs,
                                          hull_points=ends, marks=marks)
    files["validation"] = plot_validation(run.validation.lines, fig_dir / "validation.png",
                                          list(zip(global_stage.line_designs, global_stage.line_values,
                                                   strict=True)), global_stage.model)
    return {k: str(Path(v).relative_to(run.out)) for k, v in files.items()}


def _design_dict(d) -> dict:
    return {"oa": float(d[0]), "ab": float(d[1]), "bc": float(d[2])}


def write_outputs(run, engine: str, store_path: Path) -> None:
    """Write figures, result.json and report.md of a :class:`~studies.run.StudyRun` into ``run.out``."""
    out = run.out
    figures = _figures(run, out / "figures")
    study, pipeline, val = run.study, run.pipeline, run.validation
    orig = run.references.get("original")
    table = []
    for name, r in run.references.items():
        paper = study.designs.get(name, {})
        row = {"design": name, "design_mm": _design_dict(r.design), "t_rms_Nm": r.t_rms, "t_max_Nm": r.t_max,
               "feasible": r.feasible, "message": r.message,
               "paper_t_rms_Nm": paper.get("paper_t_rms_Nm"), "paper_t_max_Nm": paper.get("paper_t_max_Nm")}
        if orig is not None:
            row["t_rms_savings_pct"] = 100 * (1 - r.t_rms / orig.t_rms)
            row["t_max_savings_pct"] = 100 * (1 - r.t_max / orig.t_max)
        table.append(row)
    truth = run.truth
    best = run.references["optimum (mechopt)"]
    result = {
        "study": study.name,
        "engine": engine,
        "optimum": {"design_mm": _design_dict(best.design), "t_rms_Nm": best.t_rms, "t_max_Nm": best.t_max,
                    "predicted_t_rms_Nm": pipeline.best.predicted, "margins": best.margins},
        "designs": table,
        "simulations": {"fit": pipeline.stages[0].n_samples, "optimisation": pipeline.n_fit_simulations,
                        "validation": val.n_points,
                        "paper_fit": 618, "paper_validation": 1252},
        "stages": [s.summary() for s in pipeline.stages],
        "pipeline_message": pipeline.message,
        "validation": {"rmse_Nm": val.rmse, "rmse_low_Nm": val.rmse_low, "max_error_Nm": val.max_error,
                       "t_min_Nm": val.t_min, "n_points": val.n_points, "n_lines": len(val.lines),
                       "rmse_pct_of_t_min": 100 * val.rmse / val.t_min},
        "ground_truth": None if truth is None else {
            "design_mm": _design_dict(truth.x), "t_rms_Nm": truth.fun, "grid_mm": truth.step_mm,
            "gap_pct": 100 * (best.t_rms / truth.fun - 1)},
        "reconstruction": study.reconstruction.summary() if study.reconstruction else None,
        "options": run.options.__dict__,
        "store": str(store_path),
        "figures": figures,
        "timings_s": run.timings,
    }
    (out / "result.json").write_text(json.dumps(result, indent=2, default=float))
    (out / "report.md").write_text(_report_md(result, study))


def _report_md(r: dict, study) -> str:
    lines = [f"# Study `{r['study']}`", "", study.description, ""]
    o = r["optimum"]
    d = o["design_mm"]
    lines += [
        f"**Optimum**: |OA| = {d['oa']:.3f} mm, |AB| = {d['ab']:.3f} mm, |BC| = {d['bc']:.3f} mm — T_RMS "
        f"{o['t_rms_Nm']:.4f} N·m (model {o['predicted_t_rms_Nm']:.4f}), T_max {o['t_max_Nm']:.4f} N·m, simulated "
        f"with pymunk.", "",
        f"Simulations: {r['simulations']['fit']} on the lines of the global model (paper: 618), "
        f"{r['simulations']['optimisation'] - r['simulations']['fit']} more to confirm and refine its candidate on the "
        f"simulator, and {r['simulations']['validation']} held-out ones to validate (paper: 1252). Samples simulated "
        f"with the `{r['engine']}` engine.", "",
        "## Designs (the paper's Table 1, every design simulated here)", "",
        "| design | OA (mm) | AB (mm) | BC (mm) | T_RMS (N·m) | T_max (N·m) | T_RMS savings | T_max savings "
        "| paper T_RMS | paper T_max | feasible here |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for row in r["designs"]:
        dm = row["design_mm"]
        pr = "—" if row["paper_t_rms_Nm"] is None else f"{row['paper_t_rms_Nm']:.2f}"
        pm = "—" if row["paper_t_max_Nm"] is None else f"{row['paper_t_max_Nm']:.2f}"
        lines.append(
            f"| {row['design']} | {dm['oa']:.3f} | {dm['ab']:.3f} | {dm['bc']:.3f} | {row['t_rms_Nm']:.3f} | "
            f"{row['t_max_Nm']:.3f} | {row.get('t_rms_savings_pct', 0):.1f} % | "
            f"{row.get('t_max_savings_pct', 0):.1f} % "
            f"| {pr} | {pm} | {'yes' if row['feasible'] else 'no'} |")
    lines += ["", "Savings are relative to the original design. The paper's figures come from its CAD model of the "
              "real ventilator; ours from the reconstruction (see the README): compare savings, not absolute torques.",
              ""]
    g = r["ground_truth"]
    if g:
        gd = g["design_mm"]
        lines += ["## Against the ground truth", "",
                  f"A brute force of the analytic engine over the whole region ({g['grid_mm']:g} mm grid, then a "
                  f"constrained polish) finds |OA| = {gd['oa']:.3f}, |AB| = {gd['ab']:.3f}, |BC| = {gd['bc']:.3f} mm "
                  f"with T_RMS {g['t_rms_Nm']:.4f} N·m. The optimum found here is {g['gap_pct']:+.2f} % from it.", ""]
    v = r["validation"]
    lines += ["## Validation", "",
              f"{v['n_points']} held-out simulations on {v['n_lines']} lines in other directions than Δ, inside the "
              f"global model's hull: RMSE {v['rmse_Nm']:.4f} N·m ({v['rmse_pct_of_t_min']:.2f} % of T_min = "
              f"{v['t_min_Nm']:.3f} N·m), {v['rmse_low_Nm']:.4f} N·m where T_RMS <= 2 T_min, max error "
              f"{v['max_error_Nm']:.4f} N·m. The paper: RMSE 0.0281 N·m, 0.0153 N·m below 5 N·m.", "",
              "## Stages", "",
              "| stage | lines | samples | coverage | candidate (mm) | model (N·m) | simulated (N·m) |",
              "|---|---|---|---|---|---|---|"]
    for s in r["stages"]:
        c = s["candidate_mm"]
        lines.append(f"| {s['name']} | {s['n_lines']} | {s['n_samples']} | {s['coverage']:.0%} | "
                     f"({c[0]:.3f}, {c[1]:.3f}, {c[2]:.3f}) | {s['predicted_t_rms_Nm']:.4f} | "
                     f"{s['simulated_t_rms_Nm']:.4f} |")
    lines += ["", r["pipeline_message"], "", "## Timings", "", "| step | seconds |", "|---|---|"]
    lines += [f"| {k.removesuffix('_s')} | {t:.2f} |" for k, t in r["timings_s"].items()]
    lines += ["", "## Figures", ""]
    titles = {"torque": "Motor torque over the cycle", "mechanisms": "Mechanisms at ψ_start and ψ_end",
              "animation": "The optimum through one cycle", "slices": "Feasible region, slices at fixed |OA|",
              "region_3d": "Feasible region, sampling lines and their hull", "validation": "Validation"}
    for key, rel in r["figures"].items():
        lines += [f"### {titles.get(key, key)}", "", f"![{titles.get(key, key)}]({rel})", ""]
    return "\n".join(lines)
