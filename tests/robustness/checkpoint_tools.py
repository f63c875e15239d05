"""Crafting spate checkpoints for the robustness tests (h5py): copies with one thing changed, the
header checksum recomputed where a test wants a file that passes it (so that the check behind it is
the one exercised), raw bit flips, and the legacy format 1.

The header checksum is solver/io/checkpoint.cpp's header_checksum(): 64-bit FNV-1a over the format,
step, time, dt, dimensions, removed particles (little-endian binary) and the texts case_name,
case_yaml, steering_log, geometry_hash (each preceded by its length as 8 bytes).
"""
import shutil
import struct

import h5py
import numpy as np

FORMAT = "spate-checkpoint-3"


def fnv1a64(data):
    h = 14695981039346656037
    for b in data:
        h = ((h ^ b) * 1099511628211) & 0xFFFFFFFFFFFFFFFF
    return h


def text_attr(f, name):
    v = f.attrs.get(name, b"")
    if isinstance(v, np.ndarray):
        v = v.item()
    return v.decode() if isinstance(v, bytes) else str(v)


def header_checksum(f):
    def text(s):
        b = s.encode()
        return struct.pack("<Q", len(b)) + b
    data = (text(FORMAT) + struct.pack("<q", int(f.attrs["step"])) + struct.pack("<d", float(f.attrs["time"]))
            + struct.pack("<d", float(f.attrs["dt"])) + struct.pack("<i", int(f.attrs["dimensions"]))
            + struct.pack("<q", int(f.attrs["removed_particles"])) + text(text_attr(f, "case_name"))
            + text(text_attr(f, "case_yaml")) + text(text_attr(f, "steering_log")) + text(text_attr(f, "geometry_hash")))
    return f"{fnv1a64(data):016x}"


def set_text(f, name, value, variable_length=False):
    """A string attribute as spate writes it (fixed length), or as h5py does by default (variable)."""
    if name in f.attrs:
        del f.attrs[name]
    if variable_length:
        f.attrs[name] = value
    else:
        f.attrs.create(name, np.bytes_(value.encode() if value else b"\0"))


def resign(f):
    set_text(f, "header_checksum", header_checksum(f))


def replace_dataset(f, name, data, fletcher32=True, chunks=True, **kw):
    path = "particles/" + name
    del f[path]
    if chunks:
        f.create_dataset(path, data=data, chunks=True, fletcher32=fletcher32, **kw)
    else:
        f.create_dataset(path, data=data, **kw)


def mutant(source, target, edit):
    """Copies `source` to `target` and applies edit(h5py.File) to the copy."""
    shutil.copyfile(source, target)
    with h5py.File(target, "r+") as f:
        edit(f)
    return target


def chunk_offset(path, name):
    """Byte offset of the first chunk of particles/<name> in the file."""
    with h5py.File(path, "r") as f:
        d = f["particles/" + name]
        info = d.id.get_chunk_info(0)
        return info.byte_offset, info.size


def flip_byte(path, offset, mask=0x10):
    with open(path, "r+b") as fh:
        fh.seek(offset)
        b = fh.read(1)[0]
        fh.seek(offset)
        fh.write(bytes([b ^ mask]))


def to_legacy_format(f):
    """Format 2 as spate wrote it before the checksums (after the field registry): no removed count,
    hash or checksum, plain contiguous datasets."""
    set_text(f, "format", "spate-checkpoint-2")
    del f.attrs["format_version"]
    f.attrs["format_version"] = np.int32(2)
    for name in ("removed_particles", "geometry_hash", "header_checksum"):
        del f.attrs[name]
    for name in list(f["particles"].keys()):
        data = f["particles/" + name][...]
        replace_dataset(f, name, data, chunks=False)
