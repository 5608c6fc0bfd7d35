"""
A prefiltered cube exported as KTX2, read back
==============================================

The prefilter toolkit's ``envstudio prefilter --chain`` writes what an engine loads: a cube map
whose mip level k is the environment convolved with the normalised Phong lobe
(N + 1)/2π ⟨r, l⟩^N of its own exponent N_k = 2^(10 (1 − k/(K − 1)) + 1), so that the level a
shader reads picks the glossiness (seed 004 §4's Phong map, one per level). With ``-o
FILE.ktx2`` the chain is a KTX 2.0 file of half floats. Here the studio map at 64² a face
(7 levels, the CPU's spectral path), read back by twenty lines of NumPy written from the KTX 2.0
specification, checked texel for texel against the same chain computed in this process, and
shown level by level.
"""

import struct
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

import envstudio as es
from envstudio.core.cubemap import faces_to_cross
from envstudio.core.images import tile
from envstudio.io.images import read_environment
from envstudio.prefilter.spectral import spectral_chain
from envstudio.resources import asset_root

studio = asset_root() / "hdr" / "studio.exr"
folder = Path(tempfile.mkdtemp())
command = ["prefilter", "--chain", "--param", "cube", "--env", str(studio), "--size", "64"]
print("$ envstudio", " ".join(command).replace(str(asset_root()), "assets"), "-o studio.ktx2")
done = subprocess.run(
    [sys.executable, "-m", "envstudio", *command, "-o", "studio.ktx2"],
    cwd=folder,
    capture_output=True,
    text=True,
    check=False,
)
if done.returncode:
    raise RuntimeError(done.stderr)
print(done.stdout.strip())


# %%
# A reader: the identifier, the header's nine numbers, the index, one (offset, length) per
# level (level 0 first) and the key/value pairs.
def read_ktx2_cube(path):
    """Levels of a KTX2 RGBA16F cube, largest first, (6, n, n, 4) float16 each; its key/values."""
    data = Path(path).read_bytes()
    assert data[:12] == b"\xabKTX 20\xbb\r\n\x1a\n", "not a KTX 2.0 file"
    vk_format, _, width, _, _, _, faces, count, scheme = struct.unpack_from("<9I", data, 12)
    assert (vk_format, faces, scheme) == (97, 6, 0), "not an uncompressed RGBA16F cube"
    kvd_offset, kvd_length = struct.unpack_from("<2I", data, 56)
    levels = []
    for k in range(count):
        offset, length, _ = struct.unpack_from("<3Q", data, 80 + 24 * k)
        n = max(1, width >> k)
        levels.append(np.frombuffer(data, "<f2", length // 2, offset).reshape(6, n, n, 4))
    pairs, cursor = {}, kvd_offset
    while cursor < kvd_offset + kvd_length:
        (size,) = struct.unpack_from("<I", data, cursor)
        key, value = data[cursor + 4 : cursor + 4 + size].split(b"\0")[:2]
        pairs[key.decode()] = value.decode()
        cursor += 4 + size + (-size % 4)
    return levels, pairs


levels, pairs = read_ktx2_cube(folder / "studio.ktx2")
for key, value in pairs.items():
    print(f"{key}: {value}")

# %%
# The round trip: the same chain computed here from the library (``prefilter.spectral``) is
# what the file holds, rounded to half floats, every texel of every level; alpha is 1.
chain = spectral_chain(read_environment(studio), 64, len(levels), 10.0, 1.0)
for k, (read, level) in enumerate(zip(levels, chain, strict=True)):
    assert np.array_equal(read[..., :3], level.faces.astype(np.float16)), f"level {k}"
    assert np.all(read[..., 3] == 1)
exponents = [float(n) for n in pairs["envstudio.exponent"].split()]
assert np.allclose(exponents, [level.exponent for level in chain], rtol=1e-8)
print(f"{len(levels)} levels read back: every texel the chain's half float, N_k as written")

# %%
# Levels 0–5 as crosses (+Y above, −Y below, −X, +Z, +X, −Z across), each enlarged to level 0's
# size. Level 0 (N = 2048) still shows the softboxes; at level 5 (N ≈ 6.3) the lobe falls to
# half 26° from its axis, and a face holds little more than how much light comes from its side.
tiles = []
for k, read in enumerate(levels[:6]):
    cross = es.display(faces_to_cross(read[..., :3].astype(np.float32)))
    cross[faces_to_cross(np.ones((6, *read.shape[1:3], 1))).squeeze(-1) == 0] = 255
    cross = np.repeat(np.repeat(cross, 2**k, axis=0), 2**k, axis=1)
    picture = Image.fromarray(np.pad(cross, ((14, 0), (0, 0), (0, 0)), constant_values=255))
    label = f"level {k}: {read.shape[1]}x{read.shape[1]}, N = {exponents[k]:.4g}"
    ImageDraw.Draw(picture).text((2, 1), label, fill=(0, 0, 0))
    tiles.append(np.asarray(picture))
es.show(tile([tiles[:3], tiles[3:]]))
