"""The first mirror map's one rule (issue 46): candidates cheapest first, each scored by the share of the surface it
mirrors, until one mirrors ``plane_suffices``; the one that mirrors the most is chosen; the intrinsic mirror is a
candidate of every shape no plane mirrors."""

import pytest

from filter_symblend.auto import AutoConfig
from filter_symblend.auto.config import DEFAULT
from filter_symblend.auto.first_map import first_map
from filter_symblend.auto.pairs import spread
from filter_symblend.auto.surface import build_surface
from filter_symblend.testing import synthetic

pytestmark = pytest.mark.auto


def _maps(shares: dict) -> dict:
    """The shares of the maps tried, without the refusal's precise shares ("..., within 0.25%")."""
    return {name: share for name, share in shares.items() if not name.endswith("%")}


def test_the_search_stops_at_the_first_candidate_that_suffices_and_chooses_the_one_that_mirrors_most(remeshed_cow):
    """The remeshed cow (no vertex has an exact twin, so no tessellation mirror) bent 0.2 rad: no plane mirrors
    95 %, the field registered from the best plane does, and the search stops there; the costlier starts (the
    drifts, the field from the intrinsic mirror) are not made, while the intrinsic mirror is scored as every
    shape's no plane mirrors. With nothing sufficing (plane_suffices above 1) every candidate is made, and the
    choice is again the one that mirrors the most."""
    bent = synthetic.random_rigid(synthetic.bend(remeshed_cow.points, 0.2), 7)
    surface = build_surface(bent, remeshed_cow.faces)
    scored = spread(bent, surface.usable_index, DEFAULT.score_samples)
    found = first_map(surface, scored, DEFAULT)
    shares = _maps(found.shares)
    print({name: round(share, 3) for name, share in shares.items()})
    planes = [name for name in shares if "registration" not in name and name != "intrinsic mirror"]
    assert max(shares[name] for name in planes) < DEFAULT.plane_suffices
    assert shares["registration from the mirror plane"] >= DEFAULT.plane_suffices
    assert not any("drift" in name or name == "registration from the intrinsic mirror" for name in shares)
    assert "intrinsic mirror" in shares and found.intrinsic is not None
    assert shares[found.map.name] == max(shares.values())
    every = first_map(surface, scored, AutoConfig(plane_suffices=1.01))
    all_shares = _maps(every.shares)
    assert {"registration from the drift from the mirror plane", "registration from the intrinsic mirror"} <= set(all_shares)
    assert set(shares) < set(all_shares)
    assert all_shares[every.map.name] == max(all_shares.values())


def test_a_compressed_shape_whose_whitened_plane_mirrors_most_has_the_whitened_shapes_intrinsic_mirror_as_a_candidate(
        remeshed_cow):
    """The remeshed cow bent 0.4 rad and compressed to half obliquely: the whitened plane mirrors more than any
    plane (a compression of the whole), so where the shape may be compressed (any mode but 'articulated') the
    intrinsic mirror of the whitened shape, and a field registered from it, are candidates too, and so are the
    fields from the planes' coherent point drifts (a bend with a compression); for a posed body none of them is
    made. With nothing sufficing, every candidate is made and the one that mirrors the most is chosen."""
    from filter_symblend.auto.first_map import WHITENED_INTRINSIC
    from filter_symblend.auto.maps import WHITENED_PLANE
    deformed = synthetic.random_rigid(synthetic.compress(synthetic.bend(remeshed_cow.points, 0.4), [1, 1, 0], 0.5,
                                                         shear=0.15), 7)
    surface = build_surface(deformed, remeshed_cow.faces)
    scored = spread(deformed, surface.usable_index, DEFAULT.score_samples)
    everything = AutoConfig(plane_suffices=1.01, field_suffices=1.01)
    found = first_map(surface, scored, everything, compression=True)
    compressed = _maps(found.shares)
    posed = _maps(first_map(surface, scored, everything, compression=False).shares)
    print({name: round(share, 3) for name, share in compressed.items()})
    rigid = [name for name in compressed if "registration" not in name and "intrinsic" not in name]
    assert max(rigid, key=compressed.get) == WHITENED_PLANE
    whitened = {WHITENED_INTRINSIC, f"registration from the {WHITENED_INTRINSIC}"}
    drifts = {name for name in compressed if "drift" in name}
    assert whitened <= set(compressed) and len(drifts) == 2 and not (whitened | drifts) & set(posed)
    assert set(posed) | whitened | drifts == set(compressed)
    assert compressed[found.map.name] == max(compressed.values())


@pytest.mark.corpus
def test_on_a_posed_body_a_sound_intrinsic_mirror_is_chosen_over_a_field_that_mirrors_more(monkeypatch, bcicp):
    """On public ground truth (the BCICP dataset, read in place; skipped without it): FAUST's tr_reg_055. A field
    registered from the best plane mirrors more of the surface than the intrinsic mirror (measured 98 % against
    94 %) but slides along it (93 % of the published twins within 0.05 sqrt(area)); on a posed body the intrinsic
    mirror, sound itself, is chosen (98 % of its twins right; sharpened by a field where the field lands precisely and
    agrees). In any other mode the field that mirrors the most is chosen, as before."""
    import numpy as np
    from benchmarks.mirror_maps import surface_area, twin_errors

    from filter_symblend.auto import first_map as module
    points, faces, a, b = bcicp.shape("FAUST", "tr_reg_055")
    made, score = {}, module._Search.score

    def keeping(search, mirror):  # every map scored, by name (the last of each name: a finer registration)
        made[mirror.name] = mirror
        return score(search, mirror)
    monkeypatch.setattr(module._Search, "score", keeping)
    surface = build_surface(points, faces)
    scored = spread(points, surface.usable_index, DEFAULT.score_samples)
    found = first_map(surface, scored, DEFAULT, compression=False)
    shares = _maps(found.shares)
    scale = np.sqrt(surface_area(points, faces))
    right = {name: float(np.mean(twin_errors(mirror.predict(points), points, a, b, scale) <= 0.05))
             for name, mirror in made.items()}
    print({name: (round(shares[name], 3), round(right[name], 3)) for name in shares})
    most = max(shares, key=shares.get)
    assert found.map.name.startswith("intrinsic mirror")  # sharpened by a field where that holds, or not
    assert "registration" in most and shares[most] > shares[found.map.name]
    assert right[found.map.name] >= 0.97 and right[most] <= right[found.map.name] - 0.03
    anywhere = first_map(surface, scored, DEFAULT, compression=True)  # a shape that may be compressed: by the share
    assert _maps(anywhere.shares)[anywhere.map.name] == max(_maps(anywhere.shares).values())
    assert anywhere.map.name != "intrinsic mirror"
