"""Regenerate the "display_names" section of filter_symblend/meshlab/meshlab_filter_history.json.

pymeshlab has no call that gives a filter's MeshLab name (the one in MeshLab's Filters menu and in
the scripts MeshLab saves), but it records that name when a filter runs. So each filter is run once
with its defaults on a sphere, in a child process (some crash or hang; 20 s each), and the name it
recorded is kept. Filters that need rasters, textures or a second mesh do not run and are left out
(about 190 of pymeshlab 2025.7's 281 are found); messages name those by their pymeshlab name.

    python scripts/meshlab_display_names.py
"""

import json
import os
import pathlib
import signal
import tempfile
import xml.etree.ElementTree as ElementTree

import pymeshlab

TABLE = pathlib.Path(__file__).resolve().parents[1] / "filter_symblend" / "meshlab" / "meshlab_filter_history.json"


def recorded_name(filter_name: str) -> str | None:
    """The MeshLab name ``filter_name`` records when run on a sphere with its defaults, or None."""
    read, write = os.pipe()
    child = os.fork()
    if child == 0:
        os.close(read)
        os.chdir(tempfile.mkdtemp())  # some filters write files (e.g. cameras.out) where they run
        signal.alarm(20)
        ms = pymeshlab.MeshSet()
        ms.create_sphere(subdiv=2)
        try:
            ms.apply_filter(filter_name)
            handle, path = tempfile.mkstemp(suffix=".mlx")
            os.close(handle)
            ms.save_filter_script(path)
            names = [element.get("name") for element in ElementTree.parse(path).getroot()]
            os.unlink(path)
            os.write(write, names[-1].encode() if len(names) > 1 else b"")
        except BaseException:
            pass
        os._exit(0)
    os.close(write)
    with os.fdopen(read, "rb") as pipe:
        name = pipe.read().decode()
    os.waitpid(child, 0)
    return name or None


def main() -> None:
    table = json.loads(TABLE.read_text())
    names = {f: recorded_name(f) for f in pymeshlab.filter_list()}
    table["display_names"] = {f: name for f, name in sorted(names.items()) if name}
    TABLE.write_text(json.dumps(table, indent=1, ensure_ascii=False) + "\n")
    print(f"{len(table['display_names'])} of {len(names)} filters named in {TABLE}")


if __name__ == "__main__":
    main()
