"""Shared helpers: where the command-line binary and the real scenes are, and a PFM reader.

The package's promises are checked against the command line itself (same image, same hits),
so these tests need the `wavepath` binary: `cargo build --release` at the repository root,
or WAVEPATH_BIN. A missing binary fails the tests that need it; it never skips them.
"""

import os
import pathlib
import subprocess

import numpy as np
import pytest

REPO = pathlib.Path(__file__).resolve().parents[3]


@pytest.fixture(scope="session")
def cli():
    """Runs the `wavepath` binary; returns its CompletedProcess (fails on a non-zero exit)."""
    binary = pathlib.Path(os.environ.get("WAVEPATH_BIN", REPO / "target" / "release" / "wavepath"))
    assert binary.is_file(), f"{binary} missing: run `cargo build --release` first or set WAVEPATH_BIN"

    def run(*args, check=True):
        p = subprocess.run([str(binary), *map(str, args)], capture_output=True, text=True)
        if check:
            assert p.returncode == 0, f"wavepath {' '.join(map(str, args))} failed: {p.stderr}"
        return p

    return run


@pytest.fixture(scope="session")
def scenes():
    """The shared scenes folder (WAVEPATH_SCENES, else ../shared/scenes beside the repo)."""
    d = pathlib.Path(os.environ.get("WAVEPATH_SCENES", REPO.parent / "shared" / "scenes"))
    assert d.is_dir(), f"{d} missing: set WAVEPATH_SCENES to the shared scenes folder"
    return d


def read_pfm(path):
    """A colour PFM as a top-row-first float32 (h, w, 3) array (the file stores rows bottom-up)."""
    data = pathlib.Path(path).read_bytes()
    parts = data.split(b"\n", 3)
    assert parts[0].strip() == b"PF", f"{path}: not a colour PFM"
    w, h = map(int, parts[1].split())
    scale = float(parts[2])
    dtype = "<f4" if scale < 0 else ">f4"
    pixels = np.frombuffer(parts[3], dtype=dtype, count=w * h * 3).reshape(h, w, 3)
    return np.flipud(pixels).astype(np.float32)


def write_ray_file(path, origins, directions, tmin, tmax):
    """The peers' ray file: RAYS, u32 version 1, u64 count, then ox oy oz tmin dx dy dz tmax."""
    n = len(origins)
    rec = np.empty((n, 8), dtype="<f4")
    rec[:, 0:3] = origins
    rec[:, 3] = tmin
    rec[:, 4:7] = directions
    rec[:, 7] = tmax
    with open(path, "wb") as f:
        f.write(b"RAYS")
        f.write(np.array([1], dtype="<u4").tobytes())
        f.write(np.array([n], dtype="<u8").tobytes())
        f.write(rec.tobytes())


def read_ray_file(path):
    data = pathlib.Path(path).read_bytes()
    assert data[:4] == b"RAYS"
    n = int(np.frombuffer(data[8:16], dtype="<u8")[0])
    rec = np.frombuffer(data[16:], dtype="<f4", count=n * 8).reshape(n, 8)
    return rec[:, 0:3], rec[:, 4:7], rec[:, 3], rec[:, 7]


def read_hit_file(path):
    """A hit file as (t float32 (n,), prim uint32 (n,))."""
    data = pathlib.Path(path).read_bytes()
    n = int(np.frombuffer(data[:8], dtype="<u8")[0])
    rec = np.frombuffer(data[8:], dtype=np.dtype([("t", "<f4"), ("prim", "<u4")]), count=n)
    return rec["t"].copy(), rec["prim"].copy()
