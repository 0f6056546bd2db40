"""--auto: pairs='auto' and 'landmarks+auto' against 100 landmark pairs on deformations of rising strength, how
many landmarks landmarks+auto needs, and pairs='auto' on the Igea scan through the MeshSet filter."""

from __future__ import annotations

import numpy as np
import pymeshlab

from filter_symblend import GeometryError, symmetrize
from filter_symblend.testing import synthetic

from .accuracy import errors
from .common import EXACT, IGEA, MESHES, igea_meshes, load, table_meshes

# Strengths of the --auto deformations: bend angles (rad), (bend angle, compression factor along (1, 1, 0),
# shear) with the paper's Figure 1 last, and limb swings (rad).
AUTO_BENDS = (0.2, 0.4, 0.6, 1.2)
AUTO_BENDS_AND_COMPRESSIONS = ((0.2, 0.9, 0.05), (0.4, 0.85, 0.05), (1.2, 0.65, 0.15))
AUTO_SWINGS = (0.15, 0.3, 0.6)
AUTO_LANDMARK_COUNTS = (10, 20, 50, 100)  # landmark pairs placed for the landmarks+auto table


def auto_cases(points: np.ndarray, mesh: str):
    """(name, deformed points, limb vertices or None, mode) for the automatic-pairs table: each kind of
    deformation at increasing strength, in the mode a user would choose for it."""
    limb = synthetic.limb_weights(points, **synthetic.LIMBS[mesh])
    legs = np.flatnonzero(limb > 0.99)
    yield "exactly symmetric", points, None, "affine"
    for angle in AUTO_BENDS:
        yield f"bend {angle} rad", synthetic.bend(points, angle), None, "affine"
    for angle, factor, shear in AUTO_BENDS_AND_COMPRESSIONS:
        name = "Figure 1" if (angle, factor, shear) == (1.2, 0.65, 0.15) else f"bend {angle} + compression {factor}"
        yield name, synthetic.compress(synthetic.bend(points, angle), [1, 1, 0], factor, shear=shear), None, "affine"
    for angle in AUTO_SWINGS:
        yield f"limb swung {angle} rad", synthetic.articulate_limb(points, limb, angle), legs, "articulated"
    yield "compression 0.6 + shear 0.2", synthetic.compress(points, [1, 1, 0], 0.6, shear=0.2), None, "affine"


def auto_main(args) -> None:
    """pairs='auto' and 'landmarks+auto' beside 100 landmark pairs, deformations of rising strength."""
    header = ["mesh", "deformation", "mode", "input", "100 landmarks", "auto", "landmarks / auto", "landmarks+auto",
              "auto pairs (twins are)", "auto rounds", "s auto", "s landmarks+auto"]
    for mesh in table_meshes("shape / sym error, % of the diagonal (lower is better); landmarks / auto: ratio of "
                              "their sym errors (the target is 5 or more)", header, args.meshes):
        points, offset, partner, all_left, all_right, faces = load(MESHES[mesh])
        left, right = synthetic.farthest_point_pairs(points, offset, partner, 100)
        for name, deformed, limb, mode in auto_cases(points, mesh):
            region = slice(None) if limb is None else np.concatenate([limb, partner[limb]])
            deformed = synthetic.random_rigid(deformed, seed=7)
            try:
                automatic = symmetrize(deformed, faces=faces, pairs="auto", mode=mode)
            except GeometryError:
                automatic = None  # refused: no candidate's pairs are locally mirror-symmetric
            hybrid = symmetrize(deformed, left, right, faces=faces, pairs="landmarks+auto", mode=mode)
            landmarks = symmetrize(deformed, left, right, mode=mode)
            cells = [mode] + [errors(out, points, all_left, all_right, region) if out is not None else "refused"
                              for out in (deformed, landmarks.points, automatic and automatic.points)]
            landmark_error = synthetic.symmetry_error(landmarks.points, all_left, all_right)
            auto_error = None if automatic is None else synthetic.symmetry_error(automatic.points, all_left, all_right)
            if automatic is None or landmark_error < EXACT:
                cells.append("-")  # refused, or the landmarks are exact already
            elif auto_error < EXACT:
                cells.append("auto exact")  # every vertex paired with its true twin: no finite ratio
            else:
                cells.append(f"{landmark_error / auto_error:.1f}")
            cells.append(errors(hybrid.points, points, all_left, all_right, region))
            if automatic is None:
                cells += ["-", "-", "-"]
            else:
                rounds = automatic.report.auto_pairs
                cells += [f"{rounds.pair_count} ({rounds.twins_are})", f"{len(rounds.rounds)} ({rounds.stopped})",
                          f"{automatic.report.seconds.total:.2f}"]
            cells.append(f"{hybrid.report.seconds.total:.2f}")
            print(f"| {mesh} | {name} | " + " | ".join(cells) + " |", flush=True)


def auto_landmark_counts(args) -> None:
    """Sym error of a few landmark pairs alone and with automatic pairs added (landmarks+auto): how many
    landmarks a deformed specimen needs."""
    header = ["mesh", "deformation", "mode", *(f"{count} landmarks / +auto" for count in AUTO_LANDMARK_COUNTS)]
    for mesh in table_meshes("\nsym error, % of the diagonal: landmark pairs alone / the same pairs with "
                              "pairs='landmarks+auto'", header, args.meshes):
        points, offset, partner, all_left, all_right, faces = load(MESHES[mesh])
        for name, deformed, _, mode in auto_cases(points, mesh):
            deformed = synthetic.random_rigid(deformed, seed=7)
            cells = [mode]
            for count in AUTO_LANDMARK_COUNTS:
                left, right = synthetic.farthest_point_pairs(points, offset, partner, count)
                alone = symmetrize(deformed, left, right, mode=mode).points
                hybrid = symmetrize(deformed, left, right, faces=faces, pairs="landmarks+auto", mode=mode).points
                cells.append(" / ".join(f"{100 * synthetic.symmetry_error(out, all_left, all_right):.3f}"
                                        for out in (alone, hybrid)))
            print(f"| {mesh} | {name} | " + " | ".join(cells) + " |", flush=True)


def auto_scans() -> None:
    """pairs='auto' on the Igea scan at three sizes, through the MeshSet filter as a user runs it: time, pair
    count, mirror asymmetry before/after, two-way Hausdorff (MeshLab) between input and output."""
    if not IGEA.exists():
        print(f"\npairs='auto' on a scan: skipped, {IGEA} is absent")
        return
    print("\npairs='auto' on the Igea scan: mirror asymmetry RMS / max and two-way Hausdorff input<->output "
          "max / mean, % of the diagonal")
    print("| mesh | vertices | seconds | pairs (twins are) | rounds | asymmetry before | asymmetry after | Hausdorff in<->out |")
    print("|---|---|---|---|---|---|---|---|")
    for name, points, faces in igea_meshes():
        if name == "igea subdivided":
            continue
        ms = pymeshlab.MeshSet()
        ms.add_mesh(pymeshlab.Mesh(vertex_matrix=points, face_matrix=faces))
        report = ms.generate_symmetrized_mesh(pairs="auto")
        automatic, diagonal = report["auto_pairs"], report["diagonal"]
        before, after = report["mirror_asymmetry_before"], report["mirror_asymmetry_after"]
        hausdorff = report["hausdorff_input_output"]
        print(f"| {name} | {len(points):,} | {report['seconds']['total']:.0f} | "
              f"{automatic['pair_count']} ({automatic['twins_are']}) | {len(automatic['rounds'])} ({automatic['stopped']}) | "
              f"{100 * before['rms_relative']:.2f} / {100 * before['max_relative']:.1f} | "
              f"{100 * after['rms_relative']:.2f} / {100 * after['max_relative']:.1f} | "
              f"{100 * hausdorff['max'] / diagonal:.2f} / {100 * hausdorff['mean'] / diagonal:.3f} |", flush=True)
