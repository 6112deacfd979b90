"""The installed package carries its stub and documentation, and the stub says what the
module really takes."""

import ast
import inspect
import pathlib
import pydoc

import wavepath


def stub_path():
    return pathlib.Path(wavepath.__file__).parent / "__init__.pyi"


def test_stub_and_marker_are_installed():
    pkg = pathlib.Path(wavepath.__file__).parent
    assert stub_path().is_file(), "wavepath.pyi did not ship in the wheel"
    assert (pkg / "py.typed").is_file()


def stub_functions():
    """{qualified name: [parameter names]} of every def in the stub."""
    tree = ast.parse(stub_path().read_text())
    out = {}

    def params(f):
        a = f.args
        return [p.arg for p in a.posonlyargs + a.args + a.kwonlyargs if p.arg != "self"]

    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            out[node.name] = params(node)
        elif isinstance(node, ast.ClassDef) and node.name == "Scene":
            for f in node.body:
                if isinstance(f, ast.FunctionDef) and not any(
                    isinstance(d, ast.Name) and d.id == "property" for d in f.decorator_list
                ):
                    out[f"Scene.{f.name}"] = params(f)
    return out


def test_stub_signatures_match_the_module():
    stubs = stub_functions()
    assert {"load", "default_scene", "Scene.from_arrays", "Scene.render", "Scene.intersect", "Scene.occluded"} <= set(stubs)
    for name, names in stubs.items():
        obj = wavepath
        for part in name.split("."):
            obj = getattr(obj, part)
        real = [p for p in inspect.signature(obj).parameters if p != "self"]
        assert real == names, f"{name}: the stub says {names}, the module takes {real}"


def test_properties_in_the_stub_exist():
    tree = ast.parse(stub_path().read_text())
    scene = next(n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == "Scene")
    props = [f.name for f in scene.body if isinstance(f, ast.FunctionDef) and f.decorator_list]
    s = wavepath.default_scene()
    for p in props:
        if p in ("from_arrays",):
            continue
        getattr(s, p)


def test_help_describes_the_module():
    text = pydoc.render_doc(wavepath, renderer=pydoc.plaintext)
    for word in ("load", "default_scene", "from_arrays", "render", "intersect", "occluded", "MISS"):
        assert word in text, word
