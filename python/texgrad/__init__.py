"""texgrad: gradient-domain processing in a texture atlas, with numpy arrays in and out.

Images are H x W x C numpy arrays (or H x W for one channel), row 0 = the top of the picture as
image files, PIL and matplotlib store it; uint8, uint16, float32 and float64 are accepted in any
memory order, and an app returns the input's dtype unless ``dtype=`` says otherwise. Operators
come as ``scipy.sparse.csr_matrix`` when scipy is importable, else as ``(data, indices, indptr,
shape)`` tuples. See docs/python.md.
"""

from ._texgrad import (  # noqa: F401
    Cancelled,
    GeodesicSolver,
    InteractiveFilter,
    InvalidInputError,
    IoError,
    Mesh,
    NumericalError,
    PageLayout,
    UnsupportedError,
    __version__,
    dilate,
    filter,
    geodesic,
    lic,
    mask,
    place_on_pages,
    react,
    read_image,
    read_mesh,
    seams,
    stitch,
    write_image,
    write_texture_pages,
)
from ._texgrad import TexelDomain as _NativeTexelDomain
from ._texgrad import _read_texture_pages

import typing

try:
    import scipy.sparse as _sparse
except ImportError:  # pragma: no cover - scipy is a Debian package next to numpy
    _sparse = None


def _matrix(parts):
    """A CSR tuple (data, indices, indptr, shape) as scipy.sparse.csr_matrix when available."""
    data, indices, indptr, shape = parts
    if _sparse is None:
        return parts
    return _sparse.csr_matrix((data, indices, indptr), shape=shape)


def tqdm_callback(bar):
    """A ``progress=`` callable that drives a tqdm bar: its description is the stage, its
    position the stage's fraction of ``bar.total`` (e.g. ``tqdm(total=100)``; 1 when None)."""

    def update(stage, fraction):
        if getattr(bar, "desc", None) != stage:
            bar.set_description(stage, refresh=False)
        bar.update(fraction * (bar.total or 1) - bar.n)

    return update


class TexelDomain(_NativeTexelDomain):
    """A mesh's atlas, texel grid and operators at one resolution (n unknowns = active texels).

    ``TexelDomain(mesh, width, height, *, basis='continuous', seam_weight=0.0,
    keep_piece_integrals=True, progress=None)``. Operators are over the unknowns, on the surface
    scaled to unit area (paper Sec. 7): 1^T M 1 = 1 (times ``surface_area`` for model units).
    """

    def mass(self):
        """Mass matrix M (n x n, symmetric positive definite; 1^T M 1 = 1, the unit area)."""
        return _matrix(self._mass())

    def stiffness(self):
        """Stiffness matrix S (n x n, symmetric positive semi-definite, S 1 = 0; minus a
        Laplacian)."""
        return _matrix(self._stiffness())

    def differential(self):
        """Difference operator d (|A| x n): row (s, t) has -1 at s, +1 at t (paper Sec. 5.1)."""
        return _matrix(self._differential())

    def hodge_star1(self):
        """Whitney Hodge star *1 (|A| x |A|, SPD) on texel pairs; d^T *1 d = S (Sec. 5.2)."""
        return _matrix(self._hodge_star1())

    def divergence(self):
        """Divergence d^T *1 (n x |A|) of 1-forms on texel pairs, the sign of div_h (Sec. 5.3):
        ``divergence() @ differential() == stiffness()``. Needs scipy."""
        if _sparse is None:
            raise ImportError("divergence() needs scipy (python3-scipy)")
        return (self.differential().T @ self.hodge_star1()).tocsr()


class TexturePages(typing.NamedTuple):
    """A texture over its pages (``read_texture_pages``): the mesh placed on the layout, the
    layout image and the ``PageLayout``."""

    mesh: Mesh
    image: typing.Any
    layout: PageLayout


def read_texture_pages(mesh, *, slot="baseColor", texture=None, dtype=None):
    """Reads the mesh's ``slot`` texture over its pages (UDIM tiles, or one image per material;
    one page for a plain texture) as the CLI does: ``TexturePages(mesh, image, layout)``, the
    mesh placed on the layout (build a TexelDomain or run an app on it), the layout image (H x W
    x C, row 0 = top; the file's dtype unless ``dtype`` says otherwise) and the layout.
    ``texture`` names the image file(s) instead of the mesh's (``name.<UDIM>.png`` for tiles).
    A missing page raises ``IoError`` naming its file and the faces that need it."""
    return TexturePages(*_read_texture_pages(mesh, slot, texture, dtype))


__all__ = [
    "Cancelled",
    "GeodesicSolver",
    "InteractiveFilter",
    "InvalidInputError",
    "IoError",
    "Mesh",
    "NumericalError",
    "PageLayout",
    "TexelDomain",
    "TexturePages",
    "UnsupportedError",
    "__version__",
    "dilate",
    "filter",
    "geodesic",
    "lic",
    "mask",
    "place_on_pages",
    "react",
    "read_image",
    "read_mesh",
    "read_texture_pages",
    "seams",
    "stitch",
    "tqdm_callback",
    "write_image",
    "write_texture_pages",
]
