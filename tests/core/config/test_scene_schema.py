#!/usr/bin/env python3
"""Suite scene_schema: the JSON Schema of `sluice inspect --schema` against
the scenes of configs/ and against the loader.

1. The schema is generated from the built tree (the plugins on
   SLUICE_PLUGIN_PATH) and is itself a valid draft-07 schema.
2. Every scene file in configs/ validates against it. configs/studies/
   holds study files (docs/studies.md: title, scene, axes, measures), a
   different format: they are left out, and the test asserts that each of
   them is a study (a `scene` key, no `plugins`), so that a scene put there
   is not skipped silently.
3. Edits of two scenes that the loader refuses (`sluice check` exits 2) are
   refused by the schema too: unknown keys, wrong types, values out of
   range, bad enumerations, vectors of the wrong length for the dimensions,
   plugins of the other dimension, the retired dbc key `phase`. Edits the
   loader accepts (a plugin instance, variants) are accepted by both, so
   that the schema is not simply stricter than the loader.

Needs python3-yaml and python3-jsonschema (Debian 12: jsonschema 4.10).
Scenes are read with YAML 1.2 numbers (1e-6 is a number, as for the loader
and for editors' YAML language servers; PyYAML's YAML 1.1 rules read it as a
string)."""
import copy
import json
import os
import re
import subprocess
import sys
import tempfile

try:
    import jsonschema
    import yaml
except ImportError as missing:
    sys.exit("scene_schema: %s: install python3-jsonschema and python3-yaml "
             "(apt-get install python3-jsonschema python3-yaml)" % missing)

SOURCE = os.environ.get("SLUICE_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "../../.."))
BUILD = os.environ.get("SLUICE_BUILD_DIR", os.path.join(SOURCE, "build"))
SLUICE = os.path.join(BUILD, "sluice")
CONFIGS = os.path.join(SOURCE, "configs")
STUDIES = os.path.join(CONFIGS, "studies")


class Yaml12Loader(yaml.SafeLoader):
    """SafeLoader with YAML 1.2 floats: an exponent without a dot or sign."""


Yaml12Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)[eE][-+]?[0-9]+$"),
    list("-+0123456789."))


class SceneDumper(yaml.SafeDumper):
    """Writes None as an empty value, which the loader reads as {}."""


SceneDumper.add_representer(
    type(None), lambda dumper, _: dumper.represent_scalar("tag:yaml.org,2002:null", ""))


def read_yaml(path):
    with open(path, encoding="utf-8") as f:
        return yaml.load(f, Loader=Yaml12Loader)


failures = []


def fail(text):
    failures.append(text)
    print("FAIL: " + text)


def generate_schema():
    result = subprocess.run([SLUICE, "inspect", "--schema"], capture_output=True, text=True,
                            check=False)
    if result.returncode != 0:
        sys.exit("sluice inspect --schema exited %d: %s" % (result.returncode, result.stderr))
    schema = json.loads(result.stdout)
    jsonschema.Draft7Validator.check_schema(schema)
    return schema


def schema_errors(validator, scene):
    return sorted(validator.iter_errors(scene), key=lambda e: list(e.absolute_path))


def loader_accepts(scene, directory):
    """`sluice check` on the scene written to a file: True when it exits 0."""
    with tempfile.NamedTemporaryFile("w", suffix=".yaml", dir=directory, delete=False) as f:
        yaml.dump(scene, f, Dumper=SceneDumper, sort_keys=False)
        path = f.name
    try:
        result = subprocess.run([SLUICE, "check", path], capture_output=True, text=True,
                                check=False)
    finally:
        os.unlink(path)
    if result.returncode not in (0, 2):
        fail("sluice check exited %d: %s" % (result.returncode, result.stderr))
    return result.returncode == 0, result.stderr.strip()


def check_configs(validator):
    scenes = studies = 0
    for root, _, names in sorted(os.walk(CONFIGS)):
        for name in sorted(names):
            if not name.endswith((".yaml", ".yml")):
                continue
            path = os.path.join(root, name)
            document = read_yaml(path)
            if os.path.commonpath([path, STUDIES]) == STUDIES:
                if not isinstance(document, dict) or "scene" not in document \
                        or "plugins" in document:
                    fail("%s is in configs/studies but is not a study file" % path)
                studies += 1
                continue
            scenes += 1
            for error in schema_errors(validator, document):
                fail("%s: %s: %s" % (os.path.relpath(path, SOURCE),
                                     ".".join(str(p) for p in error.absolute_path) or "(top)",
                                     error.message))
    print("configs: %d scene files validated, %d study files left out" % (scenes, studies))
    if scenes < 20:
        fail("only %d scene files found in %s" % (scenes, CONFIGS))


def edit(scene, path, value):
    """A copy of scene with `value` at the dotted path (lists by index);
    value DELETE removes the key."""
    out = copy.deepcopy(scene)
    node = out
    keys = path.split(".")
    for key in keys[:-1]:
        node = node[int(key)] if isinstance(node, list) else node.setdefault(key, {})
    last = keys[-1]
    if value is DELETE:
        del node[last]
    elif isinstance(node, list) and int(last) == len(node):
        node.append(value)
    elif isinstance(node, list):
        node[int(last)] = value
    else:
        node[last] = value
    return out


DELETE = object()

# a weir 0.2 m high and long on the tank's floor, an entry a list of pieces
PROFILE_WALL = {"shape": "profile", "start": [2.0, 0], "heading": 90,
                "pieces": [{"piece": "line", "to": [2.0, 0.2]},
                           [{"piece": "line", "heading": 0, "length": 0.2}],
                           {"piece": "line", "to_y": 0, "heading": -90}]}

# (what, base scene, dotted path, value): each refused by the loader
REFUSED = [
    ("unknown top-level key", "2d", "partciles", {"spacing": 0.02}),
    ("unknown key in a section", "2d", "particles.spcing", 0.02),
    ("unknown plugin parameter", "2d", "plugins.tait.speed_of_sond", 60),
    ("unknown plugin, no 'plugin' key", "2d", "plugins.tiat", {}),
    ("instance of an unknown plugin", "2d", "plugins.sensors", {"plugin": "front_gaueg"}),
    ("retired key dbc.phase (radians; now phase_deg)", "2d", "plugins.dbc.phase", 0.3),
    ("unknown key in a fluid region", "2d", "geometry.fluid.0.velocty", [0, 0]),
    ("unknown key in a piece", "2d", "geometry.walls.1",
     edit(PROFILE_WALL, "pieces.0.too", [0, 0])),
    ("unknown key in a variant", "2d", "variants", {"v": {"remvoe": ["plugins.xsph"]}}),
    ("'variant' beside 'variants'", "2d_variants", "variant", "v"),
    ("wrong type: a string for a number", "2d", "time.end", "soon"),
    ("wrong type: a list for a number", "2d", "particles.spacing", [0.02]),
    ("wrong type: a number for a boolean", "2d", "plugins.dbc.clamp_density", 3),
    ("wrong type: a number for a list of points", "2d", "geometry.fluid.0",
     {"shape": "polygon", "points": 1.0}),
    ("wrong type: plugins as a list", "2d", "plugins", ["tait"]),
    ("out of range: above the maximum", "2d", "particles.smoothing_length_ratio", 10),
    ("out of range: below an exclusive minimum", "2d", "particles.spacing", 0),
    ("out of range: an integer below its minimum", "2d", "neighbour_search.batch_pairs", 1),
    ("out of range: a plugin parameter", "2d", "plugins.artificial_viscosity.alpha", -1),
    ("out of range: an arc's turn", "2d", "geometry.walls.1",
     edit(PROFILE_WALL, "pieces.1", {"piece": "arc", "radius": 0.1, "turn": 400})),
    ("bad enumeration", "2d", "initial.density", "hydrostatc"),
    ("unknown shape", "2d", "geometry.fluid.0.shape", "circle"),
    ("vector of 3 in a 2D scene", "2d", "domain.min", [-0.2, -0.2, -0.2]),
    ("plugin vector of 3 in a 2D scene", "2d", "plugins.gravity", {"acceleration": [0, 0, -9.81]}),
    ("'across' of a wall in a 2D scene", "2d", "geometry.walls.1",
     dict(PROFILE_WALL, across=[0, 1])),
    ("a 2D-only plugin in a 3D scene", "3d", "plugins.section_gauge", {"positions": [1.0]}),
    ("a polygon fluid region in a 3D scene", "3d", "geometry.fluid.0",
     {"shape": "polygon", "points": [[0, 0], [1, 0], [0, 1]]}),
    ("a 3D outline without 'across'", "3d", "geometry.walls.1",
     {"shape": "polyline", "points": [[1, 0], [2, 0.5]]}),
    ("missing required key", "2d", "time.end", DELETE),
    ("missing 'dimensions'", "2d", "dimensions", DELETE),
]

# (what, base, path, value): accepted by the loader and by the schema
ACCEPTED = [
    ("a plugin instance under a name of its own", "2d", "plugins.second_front",
     {"plugin": "front_gauge", "file": "front2.csv"}),
    ("a plugin named with its own name in 'plugin'", "2d", "plugins.tait.plugin", "tait"),
    ("an empty plugin value", "2d", "plugins.xsph", None),
    ("variants with every key", "2d", "variants",
     {"stiff": {"description": "c0 = 80 m/s", "remove": ["plugins.front_gauge"],
                "swap": {"dbc": "mdbc"}, "set": {"plugins.tait.speed_of_sound": 80}}}),
    ("a profile wall with nested pieces and angles in degrees", "2d", "geometry.walls.1",
     PROFILE_WALL),
    ("dbc's phase in degrees", "2d", "plugins.dbc.phase_deg", 90),
    ("a 3D outline with 'across'", "3d", "geometry.walls.1",
     {"shape": "polyline", "points": [[1, 0], [2, 0.5]], "across": [0, 0.5]}),
]


def check_edits(validator):
    bases = {"2d": read_yaml(os.path.join(CONFIGS, "dam_break_2d.yaml")),
             "3d": read_yaml(os.path.join(CONFIGS, "dam_break_3d.yaml"))}
    bases["2d_variants"] = edit(bases["2d"], "variants",
                                {"v": {"set": {"plugins.tait.speed_of_sound": 80}}})
    with tempfile.TemporaryDirectory() as directory:
        for base in bases.values():
            accepted, message = loader_accepts(base, directory)
            if not accepted:
                fail("the base scene is refused by the loader: " + message)
            for error in schema_errors(validator, base):
                fail("the base scene is refused by the schema: " + error.message)
        for what, base, path, value in REFUSED:
            scene = edit(bases[base], path, value)
            accepted, _ = loader_accepts(scene, directory)
            errors = schema_errors(validator, scene)
            if accepted:
                fail("%s (%s): the loader accepts it; the case tests nothing" % (what, path))
            if not errors:
                fail("%s (%s): the schema accepts what the loader refuses" % (what, path))
            else:
                print("refused: %-50s %s" % (what, errors[0].message[:70]))
        for what, base, path, value in ACCEPTED:
            scene = edit(bases[base], path, value)
            accepted, message = loader_accepts(scene, directory)
            if not accepted:
                fail("%s (%s): the loader refuses it: %s" % (what, path, message))
            for error in schema_errors(validator, scene):
                fail("%s (%s): the schema refuses it: %s at %s" %
                     (what, path, error.message, list(error.absolute_path)))
            print("accepted: %s" % what)


def main():
    schema = generate_schema()
    validator = jsonschema.Draft7Validator(schema)
    plugins = schema["properties"]["plugins"]["properties"]
    if len(plugins) < 40:
        fail("the schema lists only %d plugins: is SLUICE_PLUGIN_PATH the build's plugins?"
             % len(plugins))
    check_configs(validator)
    check_edits(validator)
    if failures:
        print("%d failures" % len(failures))
        return 1
    print("all passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
