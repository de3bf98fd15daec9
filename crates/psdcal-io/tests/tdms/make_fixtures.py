"""Writes the TDMS fixtures of psdcal-io's tests/tdms.rs and, for each, the
values an independent reader (npTDMS) finds in it.

Run from this folder:  python3 make_fixtures.py   (needs numpy and nptdms)

Each fixture NAME.tdms comes with NAME.csv: columns vx1, vx2, vy1, vy2 (the
four channels the test selects, in that order), one row per sample, as
npTDMS reads them (scaling applied), written with repr() so every float
round-trips. Files written by npTDMS's writer are contiguous and
little-endian; the interleaved big-endian file is assembled here byte by
byte from NI's published layout and checked by npTDMS's reader.
"""

import struct

import numpy as np
from nptdms import ChannelObject, GroupObject, RootObject, TdmsFile, TdmsWriter

RNG = np.random.default_rng(13)
DT = 5e-5  # 20 kHz


def write_csv(name, columns):
    with open(name + ".csv", "w") as f:
        f.write("vx1,vx2,vy1,vy2\n")
        for row in zip(*columns):
            f.write(",".join(repr(float(v)) for v in row) + "\n")


def contiguous_f64():
    """Three segments; the channels in another order than vx1..vy2, an
    extra channel and a string channel; a channel added in the second
    segment (incremental metadata)."""
    name = "contiguous_f64"
    order = ["vy2", "vx1", "vx2", "vy1"]
    data = {c: [] for c in order}
    with TdmsWriter(name + ".tdms") as w:
        for seg in range(3):
            objs = []
            if seg == 0:
                objs += [RootObject({"title": "psdcal fixture"}), GroupObject("psd", {"rig": "bench"})]
            for c in order:
                v = RNG.normal(0.0, 2.0, 64)
                data[c].append(v)
                objs.append(ChannelObject("psd", c, v, properties={"wf_increment": DT, "unit_string": "V"}))
            objs.append(ChannelObject("psd", "temperature", RNG.normal(25, 1, 10)))
            if seg >= 1:
                objs.append(ChannelObject("psd", "note", np.array(["seg %d" % seg, "x"])))
            w.write_segment(objs)
    f = TdmsFile.read(name + ".tdms")
    write_csv(name, [f["psd"][c][:] for c in ["vx1", "vx2", "vy1", "vy2"]])


def scaled_i16():
    """int16 counts with NI linear scaling (and one channel with a
    polynomial fed by a linear scale); channels ai0..ai3, default = the
    first four channels."""
    name = "scaled_i16"
    with TdmsWriter(name + ".tdms") as w:
        for seg in range(2):
            objs = []
            for i in range(4):
                props = {
                    "wf_increment": DT,
                    "NI_Scaling_Status": "unscaled",
                }
                if i == 2:
                    props.update({
                        "NI_Number_Of_Scales": np.int32(2),
                        "NI_Scale[0]_Scale_Type": "Linear",
                        "NI_Scale[0]_Linear_Slope": 10.0 / 32768.0,
                        "NI_Scale[0]_Linear_Y_Intercept": 0.0,
                        "NI_Scale[0]_Linear_Input_Source": np.uint32(0xFFFFFFFF),
                        "NI_Scale[1]_Scale_Type": "Polynomial",
                        "NI_Scale[1]_Polynomial_Coefficients_Size": np.int32(3),
                        "NI_Scale[1]_Polynomial_Coefficients[0]": 0.01,
                        "NI_Scale[1]_Polynomial_Coefficients[1]": 1.002,
                        "NI_Scale[1]_Polynomial_Coefficients[2]": -0.0005,
                        "NI_Scale[1]_Polynomial_Input_Source": np.uint32(0),
                    })
                else:
                    props.update({
                        "NI_Number_Of_Scales": np.int32(1),
                        "NI_Scale[0]_Scale_Type": "Linear",
                        "NI_Scale[0]_Linear_Slope": 10.0 / 32768.0,
                        "NI_Scale[0]_Linear_Y_Intercept": 0.001 * i,
                    })
                counts = RNG.integers(-30000, 30000, 50).astype(np.int16)
                objs.append(ChannelObject("Dev1", "ai%d" % i, counts, properties=props))
            w.write_segment(objs)
    f = TdmsFile.read(name + ".tdms")
    write_csv(name, [f["Dev1"]["ai%d" % i][:] for i in range(4)])


def f32_two_groups():
    """float32, vx in one group and vy in another: the channels must be named."""
    name = "f32_two_groups"
    with TdmsWriter(name + ".tdms") as w:
        objs = []
        for g, cs in (("x", ["vx1", "vx2"]), ("y", ["vy1", "vy2"])):
            for c in cs:
                objs.append(ChannelObject(g, c, RNG.normal(0, 1, 80).astype(np.float32),
                                          properties={"wf_increment": 1e-4}))
        w.write_segment(objs)
    f = TdmsFile.read(name + ".tdms")
    write_csv(name, [f["x"]["vx1"][:], f["x"]["vx2"][:], f["y"]["vy1"][:], f["y"]["vy2"][:]])


def be_string(s):
    b = s.encode("utf-8")
    return struct.pack(">I", len(b)) + b


def interleaved_be():
    """Big-endian, interleaved, mixed types (f64, f32, i32, f64, and an
    unselected i16). Segment 1: metadata with a new object list; segment 2:
    raw data only (the previous segment's objects); segment 3: incremental
    metadata whose channels repeat their previous index (0)."""
    name = "interleaved_be"
    chans = [("vx1", 10, ">d", 8), ("vx2", 9, ">f", 4), ("extra", 2, ">h", 2),
             ("vy1", 3, ">i", 4), ("vy2", 10, ">d", 8)]
    TOC_META, TOC_NEW, TOC_RAW, TOC_INTER, TOC_BE = 1 << 1, 1 << 2, 1 << 3, 1 << 5, 1 << 6

    def raw(n):
        out = b""
        for _ in range(n):
            for _, code, fmt, _ in chans:
                if fmt in (">d", ">f"):
                    v = float(RNG.normal(0, 3))
                else:
                    v = int(RNG.integers(-1000, 1000))
                out += struct.pack(fmt, v)
        return out

    def segment(toc, meta, data):
        lead = b"TDSm" + struct.pack("<I", toc) + struct.pack(">IQQ", 4713, len(meta) + len(data), len(meta))
        return lead + meta + data

    n = 40
    meta1 = struct.pack(">I", 2 + len(chans))
    meta1 += be_string("/") + struct.pack(">I", 0xFFFFFFFF) + struct.pack(">I", 0)
    meta1 += be_string("/'card'") + struct.pack(">I", 0xFFFFFFFF) + struct.pack(">I", 0)
    for c, code, _, _ in chans:
        meta1 += be_string("/'card'/'%s'" % c) + struct.pack(">IIIQ", 20, code, 1, n)
        meta1 += struct.pack(">I", 1) + be_string("wf_increment") + struct.pack(">Id", 10, DT)
    meta3 = struct.pack(">I", 1) + be_string("/'card'/'vx1'") + struct.pack(">I", 0) + struct.pack(">I", 0)
    body = segment(TOC_META | TOC_NEW | TOC_RAW | TOC_INTER | TOC_BE, meta1, raw(n))
    body += segment(TOC_RAW | TOC_INTER | TOC_BE, b"", raw(n) + raw(n))  # two chunks
    body += segment(TOC_META | TOC_RAW | TOC_INTER | TOC_BE, meta3, raw(n))
    with open(name + ".tdms", "wb") as f:
        f.write(body)
    f = TdmsFile.read(name + ".tdms")
    write_csv(name, [f["card"][c][:] for c in ["vx1", "vx2", "vy1", "vy2"]])
    assert len(f["card"]["vx1"][:]) == 4 * n


if __name__ == "__main__":
    contiguous_f64()
    scaled_i16()
    f32_two_groups()
    interleaved_be()
