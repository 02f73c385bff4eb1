"""``bhgrasp tune``: F3's force-based impedance (M_I, K_I) tuned with CMA-ES on chapter 4's fitness (4.49)."""

from __future__ import annotations

import argparse
import functools
import sys

from bhgrasp.cli import arguments as checked


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The search's size, seed and target."""
    parser.add_argument("--generations", type=checked.positive_int, default=10, help="CMA-ES generations")
    parser.add_argument("--population", type=checked.at_least_two, default=8, help="candidates per generation")
    parser.add_argument("--seed", type=checked.seed, default=0, help="CMA-ES seed")
    parser.add_argument("--force", type=checked.positive_float, default=6.0, help="desired contact force [N]")
    parser.add_argument("--serial", action="store_true", help="evaluate in this process instead of a process pool")


def run(args: argparse.Namespace) -> int:
    """Tune within chapter 4's bounds and print the optimum."""
    import numpy as np

    from bhgrasp.scenarios.press_fitness import TUNING_BOUNDS, TUNING_TOL_FUN, TUNING_TOL_X, impedance_fitness
    from bhgrasp.tuning import cma_es

    lower, upper = (np.log10(bound) for bound in TUNING_BOUNDS)  # physical bounds, argued in chapter 4
    print(
        f"tuning log10 (M_I [kg], K_I [N/m]) of F3's impedance for f_d = {args.force:g} N within "
        f"M_I {10 ** lower[0]:g}-{10 ** upper[0]:g} kg, K_I {10 ** lower[1]:g}-{10 ** upper[1]:g} N/m ..."
    )
    result = cma_es(
        functools.partial(impedance_fitness, force=args.force),
        x0=[-1.0, 1.5],
        sigma0=0.5,
        seed=args.seed,
        max_generations=args.generations,
        population=args.population,
        bounds=(lower, upper),
        tol_fun=TUNING_TOL_FUN,
        tol_x=TUNING_TOL_X,
        executor="serial" if args.serial else None,
        progress=sys.stderr.isatty(),  # a bar over generations on a terminal; logs stay clean
    )
    mass, stiffness = 10.0**result.best
    print(f"best M_I = {mass:.4g} kg, K_I = {stiffness:.4g} N/m: mean force error {result.best_fitness:.4f} N")
    print(f"{result.generations} generations, {result.evaluations} simulations; cma stopped on {result.criteria}")
    return 0
