"""MeshLab's PickPoints files (.pp, XML): a point with active="0" is not placed."""

from __future__ import annotations

import xml.etree.ElementTree as ElementTree

from .landmark_set import Landmark, LandmarkFileError, LandmarkSet, position_of


def read_pp(text: str, path: str) -> LandmarkSet:
    try:
        root = ElementTree.fromstring(text)
    except ElementTree.ParseError as error:
        raise LandmarkFileError(f"{path}: not a valid PickPoints XML file ({error}).") from None
    landmarks = []
    for index, point in enumerate(root.iter("point"), start=1):
        where = f"{path}, point {index} ({point.get('name', '?')})"
        position, placed = position_of([point.get(axis) for axis in "xyz"], where)
        landmarks.append(Landmark(point.get("name", f"point_{index}"), position,
                                  placed and point.get("active", "1") != "0"))
    return LandmarkSet(landmarks)


def write_pp(landmarks: LandmarkSet) -> str:
    root = ElementTree.Element("PickedPoints")
    ElementTree.SubElement(root, "DocumentData")
    for lm in landmarks.landmarks:
        x, y, z = (repr(float(v)) for v in lm.position)
        ElementTree.SubElement(root, "point", name=lm.name, active="1" if lm.placed else "0", x=x, y=y, z=z)
    ElementTree.indent(root)
    return "<!DOCTYPE PickedPoints>\n" + ElementTree.tostring(root, encoding="unicode") + "\n"
