#!/usr/bin/env python3
"""A custom objective optimised over the in-process evaluation: the index station's eight
variables of the showcase's optimize: section (Problem), scored by an objective of our own
(margin x min LCI, minus a footprint penalty), searched by scipy's differential evolution when
scipy is installed (Debian: python3-scipy), else by a plain random search. Each evaluation is a
library call (no process, no files): thousands per minute.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/optimise_objective.py [DESIGN] [EVALUATIONS]
"""
import sys
import time

import numpy as np

import fivebar

design = fivebar.load(sys.argv[1] if len(sys.argv) > 1 else "designs/iros2022.yaml")
budget = int(sys.argv[2]) if len(sys.argv) > 2 else 600
problem = fivebar.Problem(design)
lower, upper = np.array(problem.lower), np.array(problem.upper)
evaluations = 0


def objective(x):
    """To minimise: infeasible designs get their constraint violation above any feasible score."""
    global evaluations
    evaluations += 1
    c = problem.evaluate(x)
    f = c["figures"]
    if not c["feasible"]:
        return 1e3 + c["violation"]
    return -(f["margin"] * f["min_lci"]) + 1e-3 * f["footprint"]


start = time.perf_counter()
try:
    from scipy.optimize import differential_evolution
except ImportError:
    differential_evolution = None
if differential_evolution is not None:
    popsize = 10
    maxiter = max(1, budget // (popsize * len(lower)) - 1)
    result = differential_evolution(objective, list(zip(lower, upper)), popsize=popsize, maxiter=maxiter, seed=1,
                                    polish=False, tol=0)
    best_x, best_f, how = result.x, result.fun, "scipy differential_evolution"
else:
    rng = np.random.default_rng(1)
    best_x, best_f = None, np.inf
    for _ in range(budget):
        x = rng.uniform(lower, upper)
        f = objective(x)
        if f < best_f:
            best_x, best_f = x, f
    how = "random search (scipy not installed)"
seconds = time.perf_counter() - start
print(f"{how}: {evaluations} evaluations in {seconds:.1f} s ({evaluations / seconds:.0f}/s)")
reference = problem.evaluate(problem.reference_values())
best = problem.evaluate(best_x)
for name, c in (("as given", reference), ("best", best)):
    f = c["figures"]
    print(f"  {name:8s} {c['verdict']:12s} margin {f.get('margin', float('nan')):.3f} mm, "
          f"min LCI {f.get('min_lci', float('nan')):.3f}, footprint {f.get('footprint', float('nan')):.0f} mm²")
print("  variables: " + ", ".join(f"{k} = {v:.3f}" for k, v in best["x"].items()))
print(problem.design_at(best_x).to_yaml().splitlines()[0] + "  ... (design_at(x).to_yaml() writes the whole file)")
