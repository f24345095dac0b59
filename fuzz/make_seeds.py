#!/usr/bin/env python3
"""Writes the seed inputs of the file-parser fuzz targets into corpus/<target>/ (checked in;
`run-all.sh` grows and minimises the corpora from them). A DEM input is one byte choosing the
file name (src/bodies.rs DEM_NAMES), one byte of sidecar length, the sidecar, then the file.
The bake seed is a real bake of a 33 x 33 grid, made with `aerie bake`, the store seeds a
store of the same grid made with `aerie import` (AERIE names the binary, default
target/debug/aerie). corpus/store/seed_v2_valid and seed_v3_valid are stores of the same grid
written by builds of store format versions 2 and 3 (their bake sections hold one ε per tile,
then the quadrants' ε); this script does not rewrite them: they keep the readers of older
bake sections fuzzed, and `tests/tests/store.rs` runs `aerie info` on them."""
import io, json, os, struct, subprocess, sys, tempfile, zipfile, zlib

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
NAMES = ["N47E011.hgt", "N47E011.hgt.zip", "dem.tif", "dem.png", "dem.f32", "dem.u16",
         "dem.npy", "dem.npz"]


def dem_input(name, sidecar, data):
    side = json.dumps(sidecar, separators=(",", ":")).encode() if sidecar is not None else b""
    assert len(side) <= 255
    return bytes([NAMES.index(name), len(side)]) + side + data


def grid(w, h):
    return [100.0 + 3.0 * x + 7.0 * y + (x * y) % 5 for y in range(h) for x in range(w)]


def tiff(w, h, geo):
    """Baseline little-endian TIFF, one int16 strip, optional GeoTIFF tags."""
    data = b"".join(struct.pack("<h", int(v)) for v in grid(w, h))
    extra = []  # (tag, type, count, payload bytes)
    if geo:
        extra.append((33550, 12, 3, struct.pack("<3d", 30.0, 30.0, 0.0)))
        extra.append((33922, 12, 6, struct.pack("<6d", 0, 0, 0, 500000.0, 5200000.0, 0)))
        keys = [1, 1, 0, 2, 1024, 0, 1, 1, 3072, 0, 1, 32632]
        extra.append((34735, 3, len(keys), struct.pack("<%dH" % len(keys), *keys)))
        extra.append((42113, 2, 7, b"-32768\0"))
    entries = [(256, 3, 1, struct.pack("<H", w)), (257, 3, 1, struct.pack("<H", h)),
               (258, 3, 1, struct.pack("<H", 16)), (259, 3, 1, struct.pack("<H", 1)),
               (262, 3, 1, struct.pack("<H", 1)), (273, 4, 1, None),
               (277, 3, 1, struct.pack("<H", 1)), (278, 3, 1, struct.pack("<H", h)),
               (279, 4, 1, struct.pack("<I", len(data))), (339, 3, 1, struct.pack("<H", 2))]
    entries += extra
    entries.sort()
    ifd_off = 8
    ifd_len = 2 + 12 * len(entries) + 4
    blob_off = ifd_off + ifd_len
    blobs = b""
    ifd = struct.pack("<H", len(entries))
    data_off = None
    for tag, typ, count, payload in entries:
        if payload is None:  # StripOffsets, patched below
            ifd += struct.pack("<HHI", tag, typ, count) + b"DATA"
            continue
        if len(payload) <= 4:
            ifd += struct.pack("<HHI", tag, typ, count) + payload.ljust(4, b"\0")
        else:
            ifd += struct.pack("<HHII", tag, typ, count, blob_off + len(blobs))
            blobs += payload
            if len(blobs) % 2:
                blobs += b"\0"
    ifd += struct.pack("<I", 0)
    data_off = blob_off + len(blobs)
    ifd = ifd.replace(b"DATA", struct.pack("<I", data_off))
    return b"II*\0" + struct.pack("<I", ifd_off) + ifd + blobs + data


def png16(w, h):
    raw = b"".join(b"\0" + b"".join(struct.pack(">H", int(v)) for v in grid(w, h)[y * w:(y + 1) * w])
                   for y in range(h))

    def chunk(t, d):
        return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 16, 0, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def npy(w, h, descr="<f4", fortran=False):
    header = "{'descr': '%s', 'fortran_order': %s, 'shape': (%d, %d), }" % (
        descr, "True" if fortran else "False", h, w)
    pad = 64 - (10 + len(header) + 1) % 64
    header = (header + " " * pad + "\n").encode()
    fmt = {"<f4": "<f", "<f8": "<d", "<i2": "<h", "<u2": "<H"}[descr]
    vals = grid(w, h)
    data = b"".join(struct.pack(fmt, int(v) if fmt[-1] in "hH" else v)
                    for v in vals)
    return b"\x93NUMPY\x01\x00" + struct.pack("<H", len(header)) + header + data


def zipped(entries):
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z:
        for name, data in entries:
            z.writestr(name, data)
    return buf.getvalue()


def write(target, name, data):
    d = os.path.join(HERE, "corpus", target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, "seed_" + name), "wb") as f:
        f.write(data)


def write_store_seeds(store):
    """A valid store, and the same cut, bare of its trailer, with a flipped page byte and with a
    flipped bake-section byte (the trailer says where: u64 at trailer + 24)."""
    write("store", "valid", store)
    write("store", "cut", store[:len(store) // 2])
    write("store", "header_only", store[:200])
    header = struct.unpack_from("<I", store, 12)[0]
    flipped = bytearray(store)
    flipped[header + 10] ^= 0x10
    write("store", "page_flipped", bytes(flipped))
    bake_at = struct.unpack_from("<Q", store, len(store) - 48 + 24)[0]
    flipped = bytearray(store)
    flipped[bake_at + 5] ^= 0x10
    write("store", "bake_flipped", bytes(flipped))


def main():
    hgt_small = b"".join(struct.pack(">h", int(v)) for v in grid(9, 9))
    f32 = b"".join(struct.pack("<f", v) for v in grid(9, 7))
    u16 = b"".join(struct.pack("<H", int(v)) for v in grid(9, 7))
    seeds = {
        "hgt_wrong_length": dem_input("N47E011.hgt", None, hgt_small),
        "zip_hgt": dem_input("N47E011.hgt.zip", None, zipped([("N47E011.hgt", hgt_small)])),
        "zip_empty": dem_input("N47E011.hgt.zip", None, zipped([])),
        "tif_geo": dem_input("dem.tif", None, tiff(9, 7, True)),
        "tif_plain": dem_input("dem.tif", None, tiff(5, 4, False)),
        "png16": dem_input("dem.png", None, png16(9, 7)),
        "png16_sidecar": dem_input("dem.png", {"scale": 0.1, "offset": -50, "spacing_x": 10,
                                               "north_up": False}, png16(6, 5)),
        "f32": dem_input("dem.f32", {"width": 9, "height": 7, "spacing_x": 25.0,
                                     "spacing_y": 25.0}, f32),
        "f32_no_sidecar": dem_input("dem.f32", None, f32),
        "u16": dem_input("dem.u16", {"width": 9, "height": 7, "scale": 0.5, "offset": 10,
                                     "north_up": True}, u16),
        "npy_f4": dem_input("dem.npy", None, npy(9, 7)),
        "npy_i2_fortran": dem_input("dem.npy", {"spacing_x": 5}, npy(6, 5, "<i2", True)),
        "npy_f8": dem_input("dem.npy", None, npy(4, 3, "<f8")),
        "npz": dem_input("dem.npz", None, zipped([("elevation.npy", npy(9, 7)),
                                                  ("x.npy", npy(3, 1, "<f8"))])),
    }
    for name, data in seeds.items():
        write("dem", name, data)

    for name in os.listdir(os.path.join(ROOT, "config", "presets")):
        with open(os.path.join(ROOT, "config", "presets", name), "rb") as f:
            write("config", name.replace(".toml", ""), f.read())
    write("config", "empty", b"")
    write("config", "bad_key", b"[render]\nsize = \"640x360\"\nspeling = 1\n")

    aerie = os.environ.get("AERIE", os.path.join(ROOT, "target", "debug", "aerie"))
    with tempfile.TemporaryDirectory() as tmp:
        dem = os.path.join(tmp, "dem.f32")
        with open(dem, "wb") as f:
            f.write(b"".join(struct.pack("<f", v) for v in grid(33, 33)))
        with open(dem + ".json", "w") as f:
            json.dump({"width": 33, "height": 33, "spacing_x": 30.0, "spacing_y": 30.0}, f)
        out = os.path.join(tmp, "dem.aerie-bake")
        subprocess.run([aerie, "bake", "--tile-size", "9", "--out", out, dem], check=True,
                       stdout=subprocess.DEVNULL)
        with open(out, "rb") as f:
            bake = f.read()
        store_path = os.path.join(tmp, "dem.aerie")
        subprocess.run([aerie, "import", dem, "--tile-size", "9", "--page-tiles", "2",
                        "--out", store_path], check=True, stdout=subprocess.DEVNULL)
        with open(store_path, "rb") as f:
            store = f.read()
    write_store_seeds(store)
    write("bake", "valid", bake)
    write("bake", "cut", bake[:len(bake) // 2])
    write("bake", "header_only", bake[:64])
    write("bake", "not_a_bake", b"AERIEBAX" + bake[8:40])


if __name__ == "__main__":
    sys.exit(main())
