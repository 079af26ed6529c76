"""Operators from Python: the properties the paper states, and a texel-space PDE built with scipy
that reproduces the filter."""

import numpy as np
import pytest
import scipy.sparse
import scipy.sparse.linalg

import texgrad


def mesh_area(mesh):
    """3-D area of the mesh from its arrays (independent of texgrad's integration)."""
    v, f = mesh.vertices, mesh.faces
    cross = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    return 0.5 * np.linalg.norm(cross, axis=1).sum()


def test_operators_are_csr_matrices(spot_domain):
    n = spot_domain.unknowns
    for matrix in (spot_domain.mass(), spot_domain.stiffness()):
        assert isinstance(matrix, scipy.sparse.csr_matrix)
        assert matrix.shape == (n, n)


def test_stiffness_annihilates_constants(spot_domain):
    # S 1 = 0 exactly in exact arithmetic (the texel functions are a partition of unity); the
    # library forms each diagonal as minus the sum of its row's off-diagonals, so what remains is
    # the rounding of scipy's own row sums. S's entries reach 2.5e3 (a texel whose centre is 7e-5
    # texels from a seam: its function falls from 1 to 1/2 over that distance), so that rounding
    # is an ulp of 2.5e3, 4.5e-13: measured 3.6e-13 at 256^2 (4.1e-12 before).
    s = spot_domain.stiffness()
    assert np.abs(s @ np.ones(spot_domain.unknowns)).max() <= 1e-12


def test_mass_integrates_to_the_surface_area(spot_mesh, spot_domain):
    # Operators live on the surface scaled to unit area (paper Sec. 7).
    ones = np.ones(spot_domain.unknowns)
    assert ones @ (spot_domain.mass() @ ones) == pytest.approx(1.0, abs=1e-12)
    assert spot_domain.surface_area == pytest.approx(mesh_area(spot_mesh), rel=1e-9)


def test_mass_is_symmetric_positive_definite(spot_mesh):
    domain = texgrad.TexelDomain(spot_mesh, 64, 64)
    m = domain.mass()
    assert abs(m - m.T).max() == 0.0
    eigenvalues = np.linalg.eigvalsh(m.toarray())
    assert eigenvalues.min() > 0.0


def test_divergence_of_the_differential_is_the_stiffness(spot_mesh):
    domain = texgrad.TexelDomain(spot_mesh, 64, 64)
    d, star, s = domain.differential(), domain.hodge_star1(), domain.stiffness()
    assert d.shape == (star.shape[0], domain.unknowns)
    assert np.allclose(np.asarray(d.sum(axis=1)).ravel(), 0.0)  # -1 and +1 per pair
    difference = domain.divergence() @ d - s
    assert abs(difference).max() <= 1e-9 * abs(s).max()


def test_scipy_screened_poisson_matches_the_filter(spot_domain, spot_texture_file):
    """(alpha M + S) x = alpha M b with spsolve equals texgrad.filter(beta=0, solver='direct')."""
    alpha = 1e3
    image = texgrad.read_image(spot_texture_file, dtype=np.float32)
    b = spot_domain.gather(image)
    m, s = spot_domain.mass(), spot_domain.stiffness()
    x = scipy.sparse.linalg.spsolve((alpha * m + s).tocsc(), alpha * (m @ b))
    filtered = texgrad.filter(spot_domain, image, alpha=alpha, beta=0.0, solver="direct",
                              raw=True)
    # Compared in the M-norm (the L2 norm of the function on the surface) over the texels the
    # image stores: texels whose basis function barely touches the surface (mass 1e-15) are
    # determined only to the system's conditioning, by scipy as by CHOLMOD. The filter returns
    # float32, so the bound is 1e-8 plus what storing scipy's own solution in float32 costs.
    rows, cols = spot_domain.unknown_pixels.T
    stored = ((rows >= 0) & (rows < image.shape[0]) & (cols >= 0) & (cols < image.shape[1]))
    error = np.where(stored[:, None], spot_domain.gather(filtered) - x, 0.0)
    rounding = np.where(stored[:, None], x.astype(np.float32) - x, 0.0)

    def norm(e):
        return np.sqrt(np.einsum("ij,ij->", e, m @ e))

    assert norm(error) / norm(x) <= 1e-8 + norm(rounding) / norm(x)


def test_gather_scatter_round_trip(spot_domain, spot_texture_file):
    image = texgrad.read_image(spot_texture_file, dtype=np.float32)
    values = spot_domain.gather(image)
    assert values.shape == (spot_domain.unknowns, 3)
    blank = np.zeros_like(image)
    spot_domain.scatter(values, blank)
    active = spot_domain.texel_class > 0
    assert np.array_equal(blank[active], image[active])
    assert not blank[~active].any()
    rows, cols = spot_domain.unknown_pixels.T
    inside = (rows >= 0) & (rows < image.shape[0]) & (cols >= 0) & (cols < image.shape[1])
    assert np.array_equal(spot_domain.unknown_index[rows[inside], cols[inside]],
                          np.flatnonzero(inside))
