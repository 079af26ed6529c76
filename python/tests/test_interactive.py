"""The stateful solvers: a parameter change or a new source redoes only the cheap part and reaches
what a fresh solve gives."""

import numpy as np

import texgrad


def rms_over_max(distances, exact):
    finite = np.isfinite(exact)
    return np.sqrt(np.mean((distances[finite] - exact[finite]) ** 2)) / exact[finite].max()


def test_geodesic_updates_reach_the_direct_solution_after_a_new_source(spot_domain):
    # The C++ test (MultigridUpdatesMatchDirectOnSpotSlow) bounds updates 10-20 by 2.5e-4.
    solver = texgrad.GeodesicSolver(spot_domain, interactive=True)
    for vertex in (100, 2000):
        _, exact = texgrad.geodesic(spot_domain, source_vertices=[vertex], solver="direct",
                                    details=True)
        solver.set_sources(source_vertices=[vertex])
        errors = []
        for _ in range(20):
            solver.update()
            errors.append(rms_over_max(solver.distances, exact["distances"].ravel()))
        assert max(errors[9:]) <= 2.5e-4, errors
        assert errors[-1] < errors[0]


def test_interactive_filter_after_a_parameter_change_matches_a_fresh_filter(
        spot_domain, spot_texture_file):
    image = texgrad.read_image(spot_texture_file, dtype=np.float32)
    interactive = texgrad.InteractiveFilter(spot_domain, image, alpha=1e4, beta=0.0,
                                            solver="direct")
    interactive.solve()
    interactive.set_parameters(3e3, 2.0)
    interactive.step()  # the direct solver solves exactly in one step
    fresh = texgrad.filter(spot_domain, image, alpha=3e3, beta=2.0, solver="direct")
    # The right-hand side is formed from stored M x0 and S x0 instead of afresh: the two differ
    # by double rounding only, far below float32's step.
    assert np.abs(interactive.image() - fresh).max() <= 1e-6
    assert interactive.image().dtype == np.float32


def test_interactive_filter_steps_converge(spot_domain, spot_texture_file):
    image = texgrad.read_image(spot_texture_file, dtype=np.float32)
    interactive = texgrad.InteractiveFilter(spot_domain, image, beta=0.0, solver="multigrid")
    residuals = [interactive.step()["residuals"][-1] for _ in range(6)]
    assert residuals[-1] < 1e-2 * residuals[0]
