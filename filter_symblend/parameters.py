"""The one declaration of the filter's parameters.

Each parameter is declared once in ``PARAMETERS``; the Python signature, the
keyword validation and the generated documentation all come from it.
"""

from __future__ import annotations

import dataclasses
import difflib
import inspect
import math
import re
from typing import Any

import numpy as np

from .errors import ParameterError

ATTRIBUTE_NAME_PATTERN = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


@dataclasses.dataclass(frozen=True)
class Parameter:
    """One filter parameter.

    kind is "enum", "int", "float" or "string". Numbers have bounds; ``minimum_open``
    makes the lower bound exclusive. Enums list their ``choices``. ``layer`` says who takes
    it: "core" the paper's method on arrays, "pairs" where the pairs come from (automatic
    pairs), "meshset" the MeshSet filter only (attributes, selections).
    """

    name: str
    kind: str
    default: Any
    label: str
    doc: str
    unit: str = ""
    choices: tuple[str, ...] = ()
    minimum: float | None = None
    maximum: float | None = None
    minimum_open: bool = False
    layer: str = "core"

    def validate(self, value: Any) -> Any:
        """Return ``value`` converted to the parameter's type, or raise ParameterError."""
        if self.kind == "enum":
            if value not in self.choices:
                raise ParameterError(
                    f"`{self.name}` must be one of {', '.join(map(repr, self.choices))}, "
                    f"got {value!r}."
                )
            return value
        if self.kind == "string":
            if not isinstance(value, str) or not ATTRIBUTE_NAME_PATTERN.match(value):
                raise ParameterError(
                    f"`{self.name}` must be an attribute name of letters, digits and "
                    f"underscores (MeshLab expressions can only read such names), got {value!r}."
                )
            return value
        if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
            raise ParameterError(f"`{self.name}` must be a number, got {value!r}.")
        if not math.isfinite(float(value)):
            raise ParameterError(f"`{self.name}` must be finite, got {float(value)!r}.")
        if self.kind == "int":
            if float(value) != int(value):
                raise ParameterError(f"`{self.name}` must be a whole number, got {value!r}.")
            value = int(value)
        else:
            value = float(value)
        below = value <= self.minimum if self.minimum_open else value < self.minimum
        if below or value > self.maximum:
            raise ParameterError(
                f"`{self.name}` must be in {self.range_text()}, got {value!r}."
            )
        return value

    def range_text(self) -> str:
        """The valid range as interval notation, e.g. ``(0, 100]``."""
        if self.kind == "enum":
            return ", ".join(self.choices)
        if self.kind == "string":
            return "name of letters, digits, _"
        if self.kind == "int":
            return f"{self.minimum:d}..{self.maximum:d}"
        left = "(" if self.minimum_open else "["
        right = ")" if math.isinf(self.maximum) else "]"  # numbers are finite: inf itself is not valid
        return f"{left}{self.minimum:g}, {self.maximum:g}{right}"


PARAMETERS: tuple[Parameter, ...] = (
    Parameter(
        "mode", "enum", "standard", "Local symmetry model",
        "Step 1 of the paper. 'standard': no local transform (M = I). 'affine': the "
        "minimal local stretch that makes each neighbourhood mirror-symmetric, for "
        "compressed and bent fossils (Sec. 3.2). 'articulated': the minimal local "
        "rotation, for posed characters (Sec. 3.3).",
        choices=("standard", "affine", "articulated"),
    ),
    Parameter(
        "phi_width", "float", 5.0, "Global solve width (phi)",
        "Gaussian width h of the weights phi that tie neighbouring pairs together in "
        "the global solve, as a multiple of the mean distance from a landmark to its "
        "nearest landmark (the paper uses 5; see `width_spacing`). Too large shortens bent "
        "models; too small disconnects the pairs.",
        unit="x mean nearest-landmark spacing", minimum=0.5, maximum=1000.0,
    ),
    Parameter(
        "theta_width", "float", 5.0, "Local transform width (theta)",
        "Gaussian width of the neighbourhoods theta used to estimate each local "
        "symmetry in Step 1, as a multiple of the mean nearest-landmark spacing.",
        unit="x mean nearest-landmark spacing", minimum=0.5, maximum=1000.0,
    ),
    Parameter(
        "width_spacing", "float", 0.0, "Width unit",
        "The length that `phi_width` and `theta_width` multiply, in mesh units. 0: the mean "
        "distance from a landmark to its nearest landmark (the paper). Set it when landmarks are "
        "much denser in places, e.g. semilandmarks along curves, which would otherwise shrink "
        "both widths until the pairs fall apart; `symblend symmetrize --curves` sets it to the "
        "spacing of the placed points.",
        unit="mesh units", minimum=0.0, maximum=math.inf,
    ),
    Parameter(
        "alpha", "float", 0.01, "Pair-gap stiffness (alpha)",
        "Weight of the terms that keep the two sides spaced apart as in the "
        "(locally transformed) input; the paper uses 0.01.",
        minimum=0.0, maximum=100.0, minimum_open=True,
    ),
    Parameter(
        "pairs", "enum", "landmarks", "Pairs",
        "Where the mirror pairs come from. 'landmarks': the pair attribute (the paper). 'auto': found on "
        "the surface, no landmarks needed. Every vertex's twin is predicted by the mirror map that mirrors "
        "the most of the surface: the best mirror planes, the whitened plane (a shape compressed or sheared "
        "as a whole), or a smooth mirror field registered onto the surface from them, from their coherent "
        "point drift or from the shape's intrinsic mirror (a bent one); on a mesh whose vertices mirror each "
        "other the twins are exact vertices, grown from the sure ones along the surface by local mirror "
        "maps, elsewhere points of the surface. Then the output is paired again while that makes it more "
        "symmetric. A shape most of whose surface has no mirror image under any map is refused. 'landmarks+auto': the landmarks are solved first, then automatic pairs "
        "found on that output join them and the solve is repeated, so the whole surface, not only the "
        "landmarks, comes out symmetric; the landmarks are always kept and weigh `landmark_priority` times "
        "more.",
        choices=("landmarks", "auto", "landmarks+auto"), layer="pairs",
    ),
    Parameter(
        "auto_pair_count", "int", 3000, "Automatic pair count",
        "How many automatic pairs (and midline points) enter the solve, spread evenly over the surface; "
        "fewer if fewer are found. The warp is exactly symmetric at the pairs and interpolates between them.",
        minimum=10, maximum=100000, layer="pairs",
    ),
    Parameter(
        "auto_iterations", "int", 5, "Automatic pairing rounds",
        "Most pairing-and-solve rounds for 'auto' and 'landmarks+auto'; the rounds stop earlier when the "
        "output no longer changes, or when a round leaves it less mirror-symmetric (that round is not kept).",
        minimum=1, maximum=50, layer="pairs",
    ),
    Parameter(
        "landmark_priority", "float", 10.0, "Landmark priority",
        "With 'landmarks+auto': how many times more a landmark pair weighs than an automatic "
        "one in both steps of the solve.",
        minimum=1.0, maximum=1000.0, layer="pairs",
    ),
    Parameter(
        "pair_attribute", "string", "symblend_pair", "Landmark pair attribute",
        "Per-vertex custom scalar attribute holding the pairs: +k on the left vertex "
        "of pair k, -k on the right one, 0 elsewhere.",
        layer="meshset",
    ),
    Parameter(
        "midline_attribute", "string", "symblend_midline", "Midline landmark attribute",
        "Per-vertex custom scalar attribute marking midline landmarks (non-zero on them): they "
        "end up exactly on the symmetry plane. Ignored if the mesh has no such attribute.",
        layer="meshset",
    ),
    Parameter(
        "weight_attribute", "string", "symblend_weight", "Landmark weight attribute",
        "Per-vertex custom scalar attribute in [0, 1] read at the landmarks: 0 marks a missing or "
        "broken landmark, whose side then takes the mirror shape of the other side (the paper's "
        "missing regions). Ignored if the mesh has no such attribute; all weights are 1 then.",
        layer="meshset",
    ),
    Parameter(
        "missing_region", "enum", "none", "Missing region",
        "Vertices that take the mirror shape of the intact side after symmetrizing (each moves to "
        "its closest point on the reflected intact surface, faded in at the border). 'none': no "
        "fill. 'weight': vertices whose weight attribute is below 1 (by 1 - weight). 'selection': "
        "the selected vertices, and the vertices whose faces are all selected (e.g. the faces "
        "`meshing_close_holes(newfaceselected=True, refinehole=True)` just added). With 'auto' "
        "or 'landmarks+auto' these vertices are also kept out of the automatic pairs, so that "
        "they do not pull the intact side toward their shape.",
        choices=("none", "weight", "selection"), layer="meshset",
    ),
    Parameter(
        "checks", "enum", "mirror", "Before/after checks",
        "What the report measures besides the landmarks. 'mirror': the surface's mirror asymmetry before "
        "and after (max, mean, RMS, median, 90th and 99th percentiles), the distance from 5,000 evenly "
        "strided vertices to the surface reflected across the plane of the pairs solved, refined to each "
        "surface, as symblend report measures them; warnings when the output is worse than the input, is "
        "left asymmetric by automatic pairs, or the input needs nothing; a fraction of the filter's time "
        "(beside the warp). 'full': also the "
        "two-way Hausdorff distance between input and output (from at most 20,000 evenly strided vertices "
        "of each to the other surface; it about doubles the filter's time, measured at 32k vertices). "
        "'none': neither.",
        choices=("mirror", "full", "none"), layer="meshset",
    ),
    Parameter(
        "uncertainty", "enum", "none", "Uncertainty",
        "How sure the restoration is. 'jackknife': each landmark pair and midline landmark is left out in turn "
        "(beyond 100 of them, in 100 random groups) and the restoration repeated (Steps 1 and 2 again; the warp of every repetition in one evaluation); "
        "the output gets the per-vertex attribute `symblend_uncertainty` (the jackknife standard error of each "
        "restored vertex, mesh units) and the report `uncertainty` (its median, 90th percentile and max, each "
        "pair's influence: how far the result moves without it, and the most influential pair; each pair's "
        "mirror error: how far from mirroring the others' restoration leaves it, and a warning naming a pair "
        "that stands out as probably misplaced). 'placement': the same report, but `symblend_uncertainty` and "
        "its figures are how far landmarks placed with RMS error `landmark_precision` move each restored vertex "
        "(RMS over 100 random placements, mesh units): a band calibrated to your placement precision. Landmark "
        "pairs only ('landmarks'), at least 3 of them. 'none': not computed.",
        choices=("none", "jackknife", "placement"),
    ),
    Parameter(
        "landmark_precision", "float", 0.0, "Landmark precision",
        "With uncertainty='placement': how far a placed landmark lies from its true place along the surface, "
        "as an RMS distance in mesh units (place a few landmarks several times and measure their scatter, "
        "as for a study's measurement error). 0: not given.",
        unit="mesh units", minimum=0.0, maximum=math.inf,
    ),
    Parameter(
        "output_frame", "enum", "input", "Output frame",
        "'input': the result rigidly fitted back onto the input landmarks, for "
        "before/after comparison. 'canonical': symmetry plane x = 0, left (+k) "
        "landmarks at x > 0, landmark centroid at y = z = 0.",
        choices=("input", "canonical"),
    ),
)

PARAMETERS_BY_NAME = {p.name: p for p in PARAMETERS}
DEFAULTS = {p.name: p.default for p in PARAMETERS}


CORE = ("core",)
ARRAYS = ("core", "pairs")
ALL = ("core", "pairs", "meshset")


class Options(dict):
    """Every parameter of some layers, defaults filled and each value checked: what
    :func:`validate_parameters` returns, so that a door that receives one (a filter script's node, checked
    when the script is read) does not check it again."""


def validate_parameters(given: dict[str, Any], layers: tuple[str, ...] = ALL) -> Options:
    """Fill defaults, check every value; unknown names raise with the closest valid name. ``given`` already
    validated for these layers (an :class:`Options` with their parameters) is returned as it is.

    Only the parameters of ``layers`` are accepted (see :class:`Parameter`).
    """
    accepted = [p for p in PARAMETERS if p.layer in layers]
    if isinstance(given, Options) and list(given) == [p.name for p in accepted]:
        return given
    names = [p.name for p in accepted]
    for name in given:
        if name not in names:
            close = difflib.get_close_matches(name, names, n=1)
            hint = f" Did you mean `{close[0]}`?" if close else ""
            raise ParameterError(
                f"Unknown parameter `{name}`.{hint} Valid parameters: {', '.join(names)}."
            )
    return Options({p.name: p.validate(given.get(p.name, p.default)) for p in accepted})


def options_of(options: dict[str, Any], layers: tuple[str, ...]) -> dict[str, Any]:
    """The entries of ``options`` whose parameters belong to ``layers`` (e.g. CORE: what the solve takes)."""
    return {p.name: options[p.name] for p in PARAMETERS if p.layer in layers and p.name in options}


def parameters_doc(layers: tuple[str, ...] = ALL) -> str:
    """numpy-style 'Parameters' entries, pymeshlab style: ``name : type = default``."""
    lines = []
    for p in PARAMETERS:
        if p.layer not in layers:
            continue
        lines.append(f"{p.name} : {p.kind} = {p.default!r}")
        unit = f" Unit: {p.unit}." if p.unit else ""
        lines.append(f"    {p.label}. {p.doc}{unit} Valid: {p.range_text()}.")
    return "\n".join(lines)


def keyword_signature(*leading: inspect.Parameter, layers: tuple[str, ...] = ALL) -> inspect.Signature:
    """A signature with ``leading`` parameters, then one keyword per declared parameter of ``layers``."""
    keywords = [
        inspect.Parameter(p.name, inspect.Parameter.KEYWORD_ONLY, default=p.default)
        for p in PARAMETERS if p.layer in layers
    ]
    return inspect.Signature([*leading, *keywords])


def parameters_markdown() -> str:
    """The parameter table of the README, generated from the declaration."""
    rows = ["| parameter | default | valid | meaning |", "|---|---|---|---|"]
    for p in PARAMETERS:
        unit = f" Unit: {p.unit}." if p.unit else ""
        rows.append(f"| `{p.name}` | `{p.default!r}` | {p.range_text()} | {p.label}. {p.doc}{unit} |")
    return "\n".join(rows)
