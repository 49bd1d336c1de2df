#!/usr/bin/env python3
"""Writes the fuzzers' seed corpora into OUT_DIR/{xml,ply,obj,serialized,vol,btf,exr,experiment}.

xml: every scenes/*/scene.xml of the repository (as <folder>.xml) with its film shrunk to 8 x 8
pixels and 8 time bins (loading allocates the film: at the scenes' sizes, up to 200 MB, a load
takes 0.5 s under AddressSanitizer), plus meshes.xml, a small scene that reads one seed of each
binary kind (by names relative to the scene), so that mutated scenes reach those readers.
ply, obj, vol, btf: small valid files of each variant the readers handle (scenes/ holds none;
the BTFs are Bonn BDI, DFMF and FMF files of 3 directions and 2 x 2 texels, in the layout
host/src/btf/btf_write.cpp writes).
exr: small scan-line EXRs (uncompressed and ZIPS) of half and float RGB, RGBA and luminance,
one with a data window off the origin, written here from the OpenEXR file layout.
experiment: the `femto bench` experiments of bench/experiments, every file they name made
scene.xml and every plugin folder plugins (the harness writes both beside its input), and one
with a plugin folder and a reference file.

Usage: make_seeds.py REPO_DIR OUT_DIR
"""
import pathlib
import re
import shutil
import struct
import sys
import zlib

# A unit square pyramid: 5 vertices, 4 triangles and a quad base.
POSITIONS = [(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0), (0, 0, 1)]
NORMALS = [(0, 0, 1)] * 5
UVS = [(0, 0), (1, 0), (1, 1), (0, 1), (0.5, 0.5)]
FACES = [(0, 1, 4), (1, 2, 4), (2, 3, 4), (3, 0, 4), (3, 2, 1, 0)]
TRIANGLES = [f for f in FACES if len(f) == 3] + [(3, 2, 1), (3, 1, 0)]


# An experiment with a variant's plugin folder and a reference file, which no shipped one has.
PLUGIN_DIR_EXPERIMENT = """<experiment name="plugin folder">
    <scene file="scene.xml" name="s">
        <define name="res" value="8"/>
    </scene>
    <reference file="scene.xml"/>
    <variant name="a"><define name="integrator" value="path"/></variant>
    <variant name="b"><plugin_dir path="plugins"/></variant>
    <budgets spp="1 4"/>
    <seeds count="2"/>
</experiment>
"""


def ply_header(fmt, normals, uvs, extra=""):
    lines = ["ply", f"format {fmt} 1.0", "comment femto fuzz seed", f"element vertex {len(POSITIONS)}",
             "property float x", "property float y", "property float z"]
    if normals:
        lines += ["property float nx", "property float ny", "property float nz"]
    if uvs:
        lines += ["property float u", "property float v"]
    lines += [f"element face {len(FACES)}", "property list uchar int vertex_indices"]
    return ("\n".join(lines) + "\n" + extra + "end_header\n").encode()


def ply_ascii(normals=True, uvs=True):
    body = []
    for i, p in enumerate(POSITIONS):
        row = list(p) + (list(NORMALS[i]) if normals else []) + (list(UVS[i]) if uvs else [])
        body.append(" ".join(str(v) for v in row))
    for f in FACES:
        body.append(" ".join(str(v) for v in (len(f),) + f))
    return ply_header("ascii", normals, uvs) + ("\n".join(body) + "\n").encode()


def ply_binary(endian):
    fmt = "binary_little_endian" if endian == "<" else "binary_big_endian"
    # An extra element with a list and a scalar that the reader must skip.
    extra = "element material 1\nproperty list uchar float weights\nproperty double id\n"
    out = ply_header(fmt, True, True, extra)
    for i, p in enumerate(POSITIONS):
        out += struct.pack(endian + "8f", *p, *NORMALS[i], *UVS[i])
    for f in FACES:
        out += struct.pack(endian + "B" + "i" * len(f), len(f), *f)
    out += struct.pack(endian + "B2fd", 2, 0.25, 0.75, 7.0)
    return out


def obj(normals, uvs):
    lines = ["# femto fuzz seed", "o pyramid"] + [f"v {x} {y} {z}" for x, y, z in POSITIONS]
    if uvs:
        lines += [f"vt {u} {v}" for u, v in UVS]
    if normals:
        lines += [f"vn {x} {y} {z}" for x, y, z in NORMALS]
    for f in FACES:
        corners = []
        for i in f:
            k = i + 1
            corners.append(f"{k}/{k}/{k}" if normals and uvs else f"{k}//{k}" if normals
                           else f"{k}/{k}" if uvs else f"{k}")
        lines.append("f " + " ".join(corners))
    return ("\n".join(lines) + "\n").encode()


def vol(res, values, bbox=(0, 0, 0, 1, 1, 1)):
    # Mitsuba gridvolume: "VOL", version 3, encoding 1 (float32), resolution, 1 channel, bbox.
    out = b"VOL" + bytes([3]) + struct.pack("<i3ii6f", 1, *res, 1, *bbox)
    return out + struct.pack(f"<{len(values)}f", *values)


def serialized(version, wide, normals, uvs, meshes=1):
    # Mitsuba .serialized: per mesh uint16 0x041C, uint16 version, then a zlib stream (flags,
    # the name in version 4, counts, positions, normals, uvs, uint32 indices); a dictionary
    # of the meshes' offsets and their count ends the file.
    fmt = "d" if wide else "f"
    out, offsets = b"", []
    for m in range(meshes):
        flags = (0x2000 if wide else 0x1000) | (0x1 if normals else 0) | (0x2 if uvs else 0)
        body = struct.pack("<I", flags) + (b"mesh\0" if version >= 4 else b"")
        body += struct.pack("<QQ", len(POSITIONS), len(TRIANGLES))
        body += struct.pack(f"<{3 * len(POSITIONS)}{fmt}", *[c + m for p in POSITIONS for c in p])
        if normals:
            body += struct.pack(f"<{3 * len(POSITIONS)}{fmt}", *([0.0, 0.0, 1.0] * len(POSITIONS)))
        if uvs:
            body += struct.pack(f"<{2 * len(POSITIONS)}{fmt}", *([0.5, 0.5] * len(POSITIONS)))
        body += struct.pack(f"<{3 * len(TRIANGLES)}I", *[i for t in TRIANGLES for i in t])
        offsets.append(len(out))
        out += struct.pack("<HH", 0x041C, version) + zlib.compress(body)
    out += struct.pack(f"<{len(offsets)}{'Q' if version >= 4 else 'I'}", *offsets)
    return out + struct.pack("<I", meshes)


MESHES_XML = """<scene version="3.0.0">
    <sensor type="perspective">
        <film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/></film>
    </sensor>
    <emitter type="point"><point name="position" x="0" y="0" z="3"/></emitter>
    <shape type="ply"><string name="filename" value="ply/ascii.ply"/></shape>
    <shape type="serialized">
        <string name="filename" value="serialized/v3-three.serialized"/>
        <integer name="shape_index" value="2"/>
        <transform name="to_world"><translate x="-3"/></transform>
    </shape>
    <shape type="obj">
        <string name="filename" value="obj/full.obj"/>
        <transform name="to_world"><translate x="3"/></transform>
    </shape>
    <medium type="heterogeneous" id="smoke">
        <string name="density" value="vol/ramp.vol"/>
        <float name="scale" value="2"/>
    </medium>
    <shape type="cube">
        <bsdf type="null"/>
        <ref name="interior" id="smoke"/>
    </shape>
</scene>
"""


def btf_common(signature, width, height, dirs):
    meta = struct.pack("<II", 291, 4) + bytes(240) + struct.pack("<f3fIII", 1.0, 1, 1, 1, 0, 0, 3)
    meta += b"".join(struct.pack("<I", 1) + c for c in (b"R", b"G", b"B"))
    out = signature + meta + struct.pack("<I", len(dirs))
    for theta, phi in dirs:
        out += struct.pack("<ffI", theta, phi, len(dirs))
        out += b"".join(struct.pack("<ff", t, p) for t, p in dirs)
    return out + struct.pack("<II", width, height)


BTF_DIRS = [(0.0, 0.0), (0.5, 0.0), (0.5, 2.0)]


def btf(kind):
    n, w, h = len(BTF_DIRS), 2, 2
    if kind == "bdi":
        out = btf_common(b"!BDIF06R2!", w, h, BTF_DIRS) + struct.pack("<IB", 2, 2) + bytes([1] * (w * h))
        out += struct.pack("<I", 0)  # rotations
        values = [0.1 + 0.01 * i for i in range(w * 2 * n * n * 3)]
        for _ in range(h // 2):  # chunks of 2 scan lines
            out += struct.pack("<I", 2 * len(values)) + struct.pack(f"<{len(values)}e", *values)
        return out
    k = 2  # components
    fmt, size = ("<{}f", 4) if kind == "dfmf" else ("<{}e", 2)
    def matrix(rows):
        return struct.pack(fmt.format(rows * k), *[0.3 + 0.05 * (i % 5) for i in range(rows * k)])
    if kind == "dfmf":
        out = btf_common(b"!DFMF08FCR", w, h, BTF_DIRS) + struct.pack("<IIi3f9f", 0, k, 0, 0, 0, 0,
                                                                     1, 0, 0, 0, 1, 0, 0, 0, 1)
        for _ in range(3):
            out += struct.pack("<BIII", size, k, n * n, w * h) + matrix(1) + matrix(n * n) + matrix(w * h)
        return out
    out = btf_common(b"!FMF06FCR", w, h, BTF_DIRS) + struct.pack("<II", 0, k)
    return out + struct.pack("<BIII", size, k, 3 * n * n, w * h) + matrix(1) + matrix(3 * n * n) + matrix(w * h)


# OpenEXR's pixel types and the struct codes of their values.
EXR_UINT, EXR_HALF, EXR_FLOAT = 0, 1, 2
EXR_CODES = {EXR_UINT: "I", EXR_HALF: "e", EXR_FLOAT: "f"}


def exr_attribute(name, kind, value):
    return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(value)) + value


def exr_zips(raw):
    # ZIPS: the bytes split into even and odd halves, then delta-coded, then zlib.
    reordered = bytearray(raw[0::2] + raw[1::2])
    for i in range(len(reordered) - 1, 0, -1):
        reordered[i] = (reordered[i] - reordered[i - 1] + 128) % 256
    packed = zlib.compress(bytes(reordered))
    return packed if len(packed) < len(raw) else raw


def exr(channels, pixel_type, width, height, origin=(0, 0), zips=False):
    """A single-part scan-line EXR: `channels` (sorted, as the format requires) of `pixel_type`,
    a ramp of values, one scan line per block (uncompressed or ZIPS)."""
    chlist = b"".join(c.encode() + b"\0" + struct.pack("<iB3xii", pixel_type, 0, 1, 1)
                      for c in channels) + b"\0"
    x0, y0 = origin
    window = struct.pack("<4i", x0, y0, x0 + width - 1, y0 + height - 1)
    header = (exr_attribute("channels", "chlist", chlist)
              + exr_attribute("compression", "compression", bytes([2 if zips else 0]))
              + exr_attribute("dataWindow", "box2i", window)
              + exr_attribute("displayWindow", "box2i", window)
              + exr_attribute("lineOrder", "lineOrder", bytes([0]))
              + exr_attribute("pixelAspectRatio", "float", struct.pack("<f", 1))
              + exr_attribute("screenWindowCenter", "v2f", struct.pack("<2f", 0, 0))
              + exr_attribute("screenWindowWidth", "float", struct.pack("<f", 1)) + b"\0")
    start = b"\x76\x2f\x31\x01" + struct.pack("<i", 2) + header
    code = EXR_CODES[pixel_type]
    blocks = []
    for y in range(height):
        ramp = [[(c + x + y) % 7 for x in range(width)] for c in range(len(channels))]
        line = b"".join(struct.pack(f"<{width}{code}", *(v if code == "I" else v / 4 for v in row))
                        for row in ramp)
        data = exr_zips(line) if zips else line
        blocks.append(struct.pack("<ii", y0 + y, len(data)) + data)
    offset = len(start) + 8 * height
    table = b""
    for block in blocks:
        table += struct.pack("<Q", offset)
        offset += len(block)
    return start + table + b"".join(blocks)


def main():
    repo, out = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
    files = {
        "ply/ascii.ply": ply_ascii(),
        "ply/ascii-plain.ply": ply_ascii(normals=False, uvs=False),
        "ply/binary-le.ply": ply_binary("<"),
        "ply/binary-be.ply": ply_binary(">"),
        "obj/full.obj": obj(True, True),
        "obj/normals.obj": obj(True, False),
        "obj/uvs.obj": obj(False, True),
        "obj/plain.obj": obj(False, False),
        "serialized/v4.serialized": serialized(4, False, True, True),
        "serialized/v4-double.serialized": serialized(4, True, False, False),
        "serialized/v3-three.serialized": serialized(3, False, True, False, meshes=3),
        "vol/one.vol": vol((1, 1, 1), [0.5]),
        "vol/ramp.vol": vol((2, 2, 2), [0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7], (-1, -1, -1, 1, 1, 1)),
        "vol/slab.vol": vol((3, 1, 2), [1, 2, 3, 0, 0, 0], (0, 0, 0, 2, 0.5, 1)),
        "xml/meshes.xml": MESHES_XML.encode(),
        "btf/a.bdi": btf("bdi"),
        "btf/a.dfmf": btf("dfmf"),
        "btf/a.fmf": btf("fmf"),
        "exr/half-rgb.exr": exr(["B", "G", "R"], EXR_HALF, 4, 3),
        "exr/float-rgb-window.exr": exr(["B", "G", "R"], EXR_FLOAT, 3, 2, origin=(-2, 5)),
        "exr/half-rgba-zips.exr": exr(["A", "B", "G", "R"], EXR_HALF, 5, 4, zips=True),
        "exr/float-rgb-zips.exr": exr(["B", "G", "R"], EXR_FLOAT, 16, 3, zips=True),
        "exr/float-y.exr": exr(["Y"], EXR_FLOAT, 4, 4),
        "exr/uint-rgb.exr": exr(["B", "G", "R"], EXR_UINT, 2, 2),
    }
    for scene in sorted(repo.glob("scenes/*/scene.xml")):
        text = re.sub(r'(<default name="(res|bins)" value=")[0-9]+"', r'\g<1>8"', scene.read_text())
        files[f"xml/{scene.parent.name}.xml"] = text.encode()
    # femto bench's experiment files, each file they name made scene.xml and each plugin folder
    # plugins (the experiment harness writes both next to its input).
    for experiment in sorted(repo.glob("bench/experiments/*.xml")):
        text = re.sub(r'\bfile="[^"]*"', 'file="scene.xml"', experiment.read_text())
        text = re.sub(r'(<plugin_dir[^>]*\bpath=)"[^"]*"', r'\1"plugins"', text)
        files[f"experiment/{experiment.stem}.xml"] = text.encode()
    files["experiment/plugin-dir.xml"] = PLUGIN_DIR_EXPERIMENT.encode()
    if out.exists():
        shutil.rmtree(out)
    for name, data in files.items():
        path = out / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)


if __name__ == "__main__":
    main()
