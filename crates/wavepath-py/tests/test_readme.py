"""The README's "From Python" examples run as written and print what they say."""

import contextlib
import io
import re

import numpy as np

from conftest import REPO


def examples():
    text = (REPO / "README.md").read_text()
    section = text.split("## From Python", 1)[1].split("\n## ", 1)[0]
    return re.findall(r"```python\n(.*?)```", section, re.S)


def test_readme_python_examples_run():
    blocks = examples()
    assert len(blocks) == 2, "the README's From Python section should have a render and a ray-casting example"
    outputs = []
    for code in blocks:
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            exec(compile(code, "README.md", "exec"), {})
        outputs.append(out.getvalue())
    assert outputs[0].startswith("(120, 160, 3) float32")
    assert "[False False False]" in outputs[1]
    assert "4294967295" in outputs[1]  # the third ray misses


def test_readme_render_is_the_command_lines(cli, tmp_path):
    import wavepath
    from conftest import read_pfm

    image, _ = wavepath.default_scene().render(spp=16, light_samples=4, max_depth=5, resolution=(160, 120))
    cli("-s", 16, "-l", 4, "-m", 5, "-r", 160, 120, "-f", tmp_path / "x.pfm")
    assert np.array_equal(image, read_pfm(tmp_path / "x.pfm"))
