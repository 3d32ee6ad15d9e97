"""Piezoelectric patch actuator: voltage to bending moment, and the FE load it gives.

The paper (eqs. 1-7) models a surface-bonded piezo patch driven across its thickness
by the free strain ``eps_p = d31 V / t_p`` (eq. 1), the blocked stress
``sigma_p = E_p d31 V / t_p`` (eq. 2) and the bending moment of that stress about the
neutral axis of the composite section (eq. 3); the neutral axis follows from the
equilibrium of eq. 4-5 (eq. 6). In the structure the patch then acts as two equal and
opposite moments at its two edges: the pin-force model of Crawley & de Luis (1987).

Sign convention
---------------
``z`` points up from the bottom of the stack, layers are listed bottom to top. The
moment of eq. 3 is ``M_p = int sigma_p b (z - D) dz``. For a patch above the neutral
axis with ``d31 < 0`` a positive voltage (field along the poling direction) gives
``eps_p < 0``: the patch contracts in x, ``M_p < 0``, and the beam bends concave up
(curvature ``d2w/dx2 = -M_p / EI > 0``), i.e. toward the patch side: a cantilever
clamped at ``x = 0`` with the patch on top deflects its tip in +z.

In the FE model (``ry = -dw/dx``, see :mod:`mvtk.fe._beam`) the equivalent load of a
patch from ``x_a`` to ``x_b > x_a`` is ``-M_p`` on the ``ry`` DOFs of edge a and ``+M_p``
on edge b (virtual work of the actuation stress, ``int sigma_p z (-dw''/dx'') dA dx``).
:func:`edge_moment_load` applies exactly this with ``moment_per_length = M_p / b``.
The in-plane force pair of the patch (``N_p = E_p d31 V b``) is not included: with the
beam axis on the neutral axis it only stretches the beam and does not excite bending.

References
----------
Crawley, E. F. & de Luis, J. (1987). Use of piezoelectric actuators as elements of
intelligent structures. AIAA Journal 25(10), 1373-1385.
Smits, J. G., Dalke, S. I. & Cooney, T. K. (1991). The constituent equations of
piezoelectric bimorphs. Sensors and Actuators A 28, 41-61.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import DimensionError, ParameterError
from ._beam import _check_layers, ply_axial_modulus
from ._materials import PiezoMaterial, Ply
from ._model import DOF_NAMES, FEModel

__all__ = [
    "neutral_axis",
    "piezo_moment_per_volt",
    "paper_eq7_moment_per_volt",
    "edge_moment_load",
    "PiezoPatch",
]


def _layer_bounds(layers: Sequence[Ply]) -> tuple[np.ndarray, np.ndarray]:
    t = np.array([p.thickness for p in layers], dtype=float)
    z1 = np.cumsum(t)
    return z1 - t, z1


def _widths(layers: Sequence[Ply], widths, where: str) -> np.ndarray:
    if widths is None:
        return np.ones(len(layers))
    w = np.asarray(widths, dtype=float)
    if w.shape != (len(layers),):
        raise DimensionError(f"{where}: expected {len(layers)} layer widths, got shape {w.shape}")
    if not np.all(np.isfinite(w) & (w > 0)):
        raise ParameterError(f"{where}: layer widths must be positive (m), got {w.tolist()}")
    return w


def neutral_axis(layers: Sequence[Ply], widths: Sequence[float] | None = None) -> float:
    """Height of the neutral axis above the bottom of a layer stack (m).

    The paper's eq. 6 generalised to N layers of equal width:
    ``D = sum E_k (z_k1^2 - z_k0^2) / (2 sum E_k t_k)``, the modulus-weighted centroid
    (moment equilibrium of eq. 4-5). ``E_k`` is the uniaxial modulus of each ply along x
    (:func:`mvtk.fe._beam.ply_axial_modulus`, E1 for a 0 degree ply).

    Parameters
    ----------
    layers : sequence of Ply
        Bottom to top.
    widths : sequence of float, optional
        Layer widths (m) when they differ (e.g. a patch narrower than the beam); each
        term is then weighted by ``b_k``. Default: equal widths.

    Returns
    -------
    float
        ``D`` in m, measured from the bottom of the first layer.

    Examples
    --------
    1 mm steel under 1 mm aluminium: the modulus-weighted centroid
    ``sum E_k t_k z_k / sum E_k t_k`` is 0.75 mm above the bottom:

    >>> from mvtk.fe import IsotropicMaterial, Ply
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> alu = IsotropicMaterial("alu", 7.0e10, 0.33, 2700.0)
    >>> round(neutral_axis([Ply(steel, 1e-3), Ply(alu, 1e-3)]) * 1e3, 6)   # mm
    0.75
    """
    layers = _check_layers(layers, "neutral_axis")
    b = _widths(layers, widths, "neutral_axis")
    z0, z1 = _layer_bounds(layers)
    E = np.array([ply_axial_modulus(p) for p in layers])
    return float(np.sum(E * b * (z1**2 - z0**2)) / (2.0 * np.sum(E * b * (z1 - z0))))


def piezo_moment_per_volt(
    layers: Sequence[Ply], piezo_index: int, width: float = 1.0,
    widths: Sequence[float] | None = None,
) -> float:
    """Bending moment per volt of one piezo layer about the composite neutral axis.

    Direct integration of the paper's eq. 3 with the stress of eq. 2 and ``D`` of
    eq. 6 (:func:`neutral_axis`)::

        M_p / V = int_{z0 - D}^{z1 - D} (E_p d31 / t_p) b z dz
                = E_p d31 b ((z1 - D)^2 - (z0 - D)^2) / (2 t_p)

    Parameters
    ----------
    layers : sequence of Ply
        The whole stack at the patch, bottom to top (substrate, bonding, piezo, ...).
    piezo_index : int
        Index in ``layers`` of the driven layer; its material must be a
        :class:`~mvtk.fe.PiezoMaterial`. The voltage is applied across that layer only.
    width : float
        Patch width b in m. The default 1.0 gives the moment per metre of width,
        N m/(V m).
    widths : sequence of float, optional
        Widths of all layers (m) when they differ, e.g. a patch narrower than the
        substrate; ``D`` then accounts for them and ``b = widths[piezo_index]``
        (``width`` must then be left at its default).

    Returns
    -------
    float
        ``M_p / V`` in N m/V (negative for a layer above the neutral axis with
        d31 < 0; see the module's sign convention).

    Examples
    --------
    A 0.2 mm PZT patch bonded (50 um epoxy) on 1 mm steel, 20 mm wide; the same as the
    closed form of :func:`paper_eq7_moment_per_volt`:

    >>> from mvtk.fe import IsotropicMaterial, PiezoMaterial, Ply
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> epoxy = IsotropicMaterial("epoxy", 3e9, 0.35, 1200.0)
    >>> pzt = PiezoMaterial("PIC151", 6.7e10, 0.34, 7800.0, d31=-2.1e-10)
    >>> mp = piezo_moment_per_volt([Ply(steel, 1e-3), Ply(epoxy, 5e-5), Ply(pzt, 2e-4)], 2,
    ...                            width=0.02)
    >>> round(mp * 1e6, 3)          # 1e-6 N m/V
    -171.847
    """
    layers = _check_layers(layers, "piezo_moment_per_volt")
    idx = int(piezo_index)
    if idx != piezo_index or not -len(layers) <= idx < len(layers):
        raise ParameterError(
            f"piezo_moment_per_volt: piezo_index must be an integer in 0..{len(layers) - 1}, "
            f"got {piezo_index!r}"
        )
    idx %= len(layers)
    mat = layers[idx].material
    if not isinstance(mat, PiezoMaterial):
        raise ParameterError(
            f"piezo_moment_per_volt: layer {idx} ({mat.name!r}) is a "
            f"{type(mat).__name__}, expected a PiezoMaterial with d31"
        )
    b = float(width)
    if not (np.isfinite(b) and b > 0):
        raise ParameterError(f"piezo_moment_per_volt: width must be positive (m), got {width!r}")
    if widths is not None:
        if b != 1.0:
            raise ParameterError(
                "piezo_moment_per_volt: give either width or widths, not both "
                f"(width={width!r}, widths={list(widths)!r})"
            )
        b = float(_widths(layers, widths, "piezo_moment_per_volt")[idx])
    D = neutral_axis(layers, widths)
    z0, z1 = _layer_bounds(layers)
    tp = z1[idx] - z0[idx]
    Ep = ply_axial_modulus(layers[idx])
    return float(Ep * mat.d31 / tp * b * ((z1[idx] - D) ** 2 - (z0[idx] - D) ** 2) / 2.0)


def paper_eq7_moment_per_volt(
    *, E_p: float, E_a: float, E_b: float, t_p: float, t_a: float, t_b: float, d31: float,
    width: float = 1.0,
) -> float:
    """The paper's closed form eq. 7 exactly as printed (N m/V).

    ``M_p / V = [E_p E_a (t_p t_a + t_a^2) + E_p E_b (t_b^2 + t_p t_b + 2 t_a t_b)]
    / (E_p t_p + E_a t_a + E_b t_b) * d31 b / 2``

    for a beam (b), adhesive (a) and piezo (p) stack, bottom to top. Checked in the tests
    against :func:`piezo_moment_per_volt`: eq. 7 as printed agrees with the direct
    integration of eq. 3 (no typo in the printed equation).

    Parameters
    ----------
    E_p, E_a, E_b : float
        Young's moduli of piezo, adhesive and beam (Pa).
    t_p, t_a, t_b : float
        Thicknesses (m).
    d31 : float
        Piezoelectric charge constant (m/V).
    width : float
        Width b (m); 1.0 gives N m/(V m).

    Examples
    --------
    The stack of :func:`piezo_moment_per_volt`'s example:

    >>> mp = paper_eq7_moment_per_volt(E_p=6.7e10, E_a=3e9, E_b=2.1e11, t_p=2e-4, t_a=5e-5,
    ...                                t_b=1e-3, d31=-2.1e-10, width=0.02)
    >>> round(mp * 1e6, 3)          # 1e-6 N m/V
    -171.847
    """
    vals = {"E_p": E_p, "E_a": E_a, "E_b": E_b, "t_p": t_p, "t_a": t_a, "t_b": t_b,
            "width": width}
    for key, v in vals.items():
        if not (np.isfinite(v) and v > 0):
            raise ParameterError(f"paper_eq7_moment_per_volt: {key} must be positive, got {v!r}")
    num = E_p * E_a * (t_p * t_a + t_a**2) + E_p * E_b * (t_b**2 + t_p * t_b + 2 * t_a * t_b)
    den = E_p * t_p + E_a * t_a + E_b * t_b
    return float(num / den * d31 * width / 2.0)


def _tributary_lengths(points: np.ndarray) -> np.ndarray:
    """Trapezoidal tributary length of each point on a straight edge line (m)."""
    centred = points - points.mean(axis=0)
    _, _, vt = np.linalg.svd(centred, full_matrices=False)
    s = centred @ vt[0]
    order = np.argsort(s)
    ss = s[order]
    w = np.zeros(len(ss))
    seg = np.diff(ss)
    w[:-1] += seg / 2.0
    w[1:] += seg / 2.0
    out = np.empty_like(w)
    out[order] = w
    return out


def _edge_nodes(model: FEModel, edge, label: str) -> np.ndarray:
    if isinstance(edge, str):
        nodes = model.node_set(edge)
    else:
        nodes = np.atleast_1d(np.asarray(edge))
        if nodes.size and nodes.dtype.kind not in "iu":
            raise ParameterError(
                f"edge_moment_load: {label} must be a node-set name or integer node indices, "
                f"got dtype {nodes.dtype}"
            )
    nodes = np.unique(nodes.astype(np.int64))
    if nodes.size == 0:
        raise ParameterError(f"edge_moment_load: {label} has no nodes")
    if nodes.min() < 0 or nodes.max() >= model.n_nodes:
        raise ParameterError(
            f"edge_moment_load: {label} refers to node(s) outside 0..{model.n_nodes - 1}"
        )
    return nodes


def edge_moment_load(
    model: FEModel,
    edge_a_nodes,
    edge_b_nodes,
    moment_per_length: float,
    component: str = "ry",
    width: float | None = None,
) -> np.ndarray:
    """Free-DOF load vector of equal and opposite line moments on two patch edges.

    Edge a gets ``-moment_per_length`` and edge b ``+moment_per_length`` (N m/m), each
    distributed over its nodes by the trapezoidal tributary length along the edge line.
    With edge a the patch edge at smaller x, edge b at larger x, ``component="ry"`` and
    ``moment_per_length = M_p / b`` from :func:`piezo_moment_per_volt`, this is the
    pin-force equivalent of the patch (see the module's sign convention).

    Parameters
    ----------
    model : FEModel
    edge_a_nodes, edge_b_nodes : str or array_like of int
        Node-set names or node indices of the two edges. An edge of a single node (a
        beam) gets ``moment_per_length * width``.
    moment_per_length : float
        Line moment, N m/m (per volt if the caller wants a load per volt).
    component : str
        Rotational DOF carrying the moment: ``"rx"``, ``"ry"`` or ``"rz"``.
    width : float, optional
        Edge length of single-node edges, m. Default: ``model.meta["width"]``.

    Returns
    -------
    ndarray, shape (n_dof,)
        Load vector over the model's free DOFs. Loads falling on constrained DOFs (an
        edge on a clamp) are dropped: the support reacts them.

    Raises
    ------
    ParameterError
        Unknown component or node set, bad node indices, overlapping edges, a missing
        width for a single-node edge, or when the moment DOFs of both edges are all
        constrained (the load would vanish).

    Examples
    --------
    Equal and opposite line moments of 1 N m/m on the two edges of a 20 mm wide patch:
    0.02 N m at each edge, no net moment:

    >>> from mvtk.fe import BeamPatch, IsotropicMaterial, Ply, cantilever_beam
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=20,
    ...                        patches=[BeamPatch("p", 0.05, 0.10, layers=(Ply(steel, 1e-4),))])
    >>> f = edge_moment_load(beam, beam.node_sets["patch:p:x0"], beam.node_sets["patch:p:x1"],
    ...                      1.0, component="ry", width=0.02)
    >>> np.round(f[f != 0], 6), float(f.sum())
    (array([-0.02,  0.02]), 0.0)
    """
    if component not in ("rx", "ry", "rz"):
        raise ParameterError(
            f"edge_moment_load: component must be one of 'rx', 'ry', 'rz', got {component!r}"
        )
    m = float(moment_per_length)
    if not np.isfinite(m):
        raise ParameterError(f"edge_moment_load: moment_per_length must be finite, got {m!r}")
    a = _edge_nodes(model, edge_a_nodes, "edge a")
    b = _edge_nodes(model, edge_b_nodes, "edge b")
    if np.intersect1d(a, b).size:
        raise ParameterError(
            f"edge_moment_load: edges a and b share node(s) {np.intersect1d(a, b)[:5].tolist()}"
        )
    c = DOF_NAMES.index(component)
    f = np.zeros(model.n_dof)
    n_applied = 0
    for nodes, sign in ((a, -1.0), (b, 1.0)):
        if nodes.size == 1:
            w = model.meta.get("width") if width is None else width
            if w is None:
                raise ParameterError(
                    "edge_moment_load: an edge with a single node needs its width; pass "
                    "width= (m) or build the model with meta['width']"
                )
            w = float(w)
            if not (np.isfinite(w) and w > 0):
                raise ParameterError(f"edge_moment_load: width must be positive (m), got {w!r}")
            lengths = np.array([w])
        else:
            lengths = _tributary_lengths(model.nodes[nodes])
        dof = model._lookup[nodes * 6 + c]
        ok = dof >= 0
        f[dof[ok]] += sign * m * lengths[ok]
        n_applied += int(ok.sum())
    if n_applied == 0:
        raise ParameterError(
            f"edge_moment_load: every {component} DOF of both edges is constrained; "
            "the moment pair would have no effect"
        )
    return f


def _stack_under_patch(model: FEModel, patch_name: str):
    """(layers, widths) of the section under a cantilever_beam patch, from model.meta."""
    info = [p for p in model.meta.get("patches", []) if p.get("name") == patch_name]
    if not info or "section_layers" not in model.meta:
        raise ParameterError(
            f"patch {patch_name!r}: the model has no such beam patch in meta['patches']; "
            "pass layers= explicitly"
        )
    x = model.nodes[:, 0]
    conn = model.elements["beam2"]
    xm = 0.5 * (x[conn[:, 0]] + x[conn[:, 1]])
    inside = (xm > info[0]["x0"]) & (xm < info[0]["x1"])
    secs = np.unique(np.asarray(model.meta["element_section"])[inside])
    if secs.size != 1:
        raise ParameterError(
            f"patch {patch_name!r} overlaps other patches ({secs.size} different sections "
            "under it); pass layers= and piezo_index= explicitly"
        )
    s = int(secs[0])
    return tuple(model.meta["section_layers"][s]), tuple(model.meta["section_layer_widths"][s])


@dataclass(frozen=True)
class PiezoPatch:
    """A piezo patch actuator on an FE model.

    Parameters
    ----------
    name : str
    layers : tuple of Ply
        The whole stack at the patch (substrate, bonding layer, piezo), bottom to top.
    piezo_index : int
        Index of the driven piezo layer in ``layers``.
    edges : tuple (edge_a, edge_b)
        Node-set names or node-index arrays of the patch edges, edge a at smaller x.
    width : float
        Patch width b (m), the width of the piezo layer.
    component : str
        Rotational DOF of the edge moments, ``"ry"`` for a patch along x.
    layer_widths : tuple of float, optional
        Widths of all layers of ``layers`` (m) when they differ (patch narrower than
        the substrate); ``layer_widths[piezo_index]`` must equal ``width``.

    Examples
    --------
    A 0.2 mm PZT layer on a 2 mm steel strip, 20 mm wide, between the patch edges of a
    cantilever: the load per volt is the moment pair ``M_p / V`` of
    :func:`piezo_moment_per_volt` at the two edges:

    >>> from mvtk.fe import BeamPatch, IsotropicMaterial, PiezoMaterial, Ply, cantilever_beam
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> pzt = PiezoMaterial("PIC151", 6.7e10, 0.34, 7800.0, d31=-2.1e-10)
    >>> stack = (Ply(steel, 2e-3), Ply(pzt, 2e-4))
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=20,
    ...                        patches=[BeamPatch("p", 0.05, 0.10, layers=stack[1:])])
    >>> patch = PiezoPatch("p", stack, 1, ("patch:p:x0", "patch:p:x1"), width=0.02)
    >>> f = patch.load_vector(beam)                                 # N m per V
    >>> np.round(f[f != 0] * 1e6, 2), round(piezo_moment_per_volt(stack, 1, width=0.02) * 1e6, 2)
    (array([ 299.97, -299.97]), -299.97)
    """

    name: str
    layers: tuple[Ply, ...]
    piezo_index: int
    edges: tuple
    width: float
    component: str = "ry"
    layer_widths: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "layers", _check_layers(self.layers, f"patch {self.name!r}"))
        if len(self.edges) != 2:
            raise DimensionError(
                f"patch {self.name!r}: edges must be a pair (edge_a, edge_b), "
                f"got {len(self.edges)} item(s)"
            )
        # validates index, material and width
        piezo_moment_per_volt(self.layers, self.piezo_index, self.width)
        if self.layer_widths is not None:
            object.__setattr__(self, "layer_widths", tuple(float(w) for w in self.layer_widths))
            bw = _widths(self.layers, self.layer_widths, f"patch {self.name!r}")
            if not np.isclose(bw[self.piezo_index], self.width, rtol=1e-12):
                raise ParameterError(
                    f"patch {self.name!r}: width {self.width} m differs from the piezo layer "
                    f"width {bw[self.piezo_index]} m in layer_widths"
                )

    @property
    def moment_per_volt(self) -> float:
        """Edge moment per volt of the whole patch width, N m/V (eq. 3 integrated)."""
        if self.layer_widths is None:
            return piezo_moment_per_volt(self.layers, self.piezo_index, self.width)
        return piezo_moment_per_volt(self.layers, self.piezo_index,
                                     widths=self.layer_widths)

    @classmethod
    def on_beam(cls, model: FEModel, patch_name: str, layers: Sequence[Ply] | None = None,
                piezo_index: int | None = None, width: float | None = None) -> PiezoPatch:
        """Patch on a :func:`~mvtk.fe.cantilever_beam` model using its patch node sets.

        Parameters
        ----------
        model : FEModel
            Built by :func:`~mvtk.fe.cantilever_beam` with a patch ``patch_name``.
        patch_name : str
        layers : sequence of Ply, optional
            Full stack at the patch, bottom to top. Default: the model's section stack
            under the patch (``meta["section_layers"]``, with its layer widths).
        piezo_index : int, optional
            Driven layer; default the single PiezoMaterial layer of the stack.
        width : float, optional
            Piezo width (m) when ``layers`` is given; default ``model.meta["width"]``.
        """
        edges = (f"patch:{patch_name}:x0", f"patch:{patch_name}:x1")
        for e in edges:
            model.node_set(e)
        widths = None
        if layers is None:
            layers, widths = _stack_under_patch(model, patch_name)
        layers = _check_layers(layers, f"patch {patch_name!r}")
        if piezo_index is None:
            found = [i for i, p in enumerate(layers) if isinstance(p.material, PiezoMaterial)]
            if len(found) != 1:
                raise ParameterError(
                    f"patch {patch_name!r}: expected exactly one PiezoMaterial layer in the "
                    f"stack, found {len(found)} (indices {found}); pass piezo_index="
                )
            piezo_index = found[0]
        if widths is not None:
            w = widths[piezo_index]
        else:
            w = model.meta.get("width") if width is None else width
            if w is None:
                raise ParameterError(
                    f"patch {patch_name!r}: pass width= (m); the model has none"
                )
        return cls(name=patch_name, layers=tuple(layers), piezo_index=int(piezo_index),
                   edges=edges, width=float(w), layer_widths=widths)

    def load_vector(self, model: FEModel, voltage: float = 1.0) -> np.ndarray:
        """Free-DOF load vector of the patch at ``voltage`` (V); N m on rotations."""
        return edge_moment_load(
            model, self.edges[0], self.edges[1],
            self.moment_per_volt / self.width * float(voltage),
            component=self.component, width=self.width,
        )
