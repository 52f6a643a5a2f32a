"""The multi-objective peers spend their budget on the problem itself and record every evaluation."""

from __future__ import annotations

import numpy as np
import pytest

from mechopt.optimize.baselines.multi_objective_peers import MULTI_OBJECTIVE_PEERS
from mechopt.studies.multi_objective_functions import BNH

BUDGETS = {"pymoo_nsga2": 20, "optuna_tpe": 20, "optuna_gp": 12, "botorch_qlognehvi": 8}


@pytest.mark.parametrize("name", sorted(MULTI_OBJECTIVE_PEERS))
def test_peer_records_every_evaluation_of_its_budget(name):
    pytest.importorskip("pymoo" if name == "pymoo_nsga2" else "optuna")
    if name in ("optuna_gp", "botorch_qlognehvi"):
        pytest.importorskip("torch")
    if name == "botorch_qlognehvi":
        pytest.importorskip("botorch")
    p = BNH()
    X, F, G = MULTI_OBJECTIVE_PEERS[name](p, BUDGETS[name], 0).arrays()
    assert X.shape == (BUDGETS[name], 2) and F.shape == (BUDGETS[name], 2) and G.shape == (BUDGETS[name], 2)
    assert np.all(p.in_box(X))
    F_true, G_true = p.function(X)
    assert np.allclose(F, F_true) and np.allclose(G, G_true)
