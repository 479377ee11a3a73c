#!/usr/bin/env python3
"""Writes the hand-made seed inputs of fuzz_commands into test/fuzz/corpus/commands/.

The harness reads its bytes with LLVM's FuzzedDataProvider, which takes integers from the END
of the input (most significant byte first) and strings from the front; this encoder mirrors the
order in which fuzz_commands.cpp consumes them, so each seed is a readable message below.
    /usr/bin/python3 test/fuzz/make_command_seeds.py
"""
import math
import os
import struct

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "corpus", "commands")
F3R_MAX_Q = 69


class Seed:
    def __init__(self):
        self.front = b""   # strings, consumed from the front
        self.tail = []     # integer bytes in the order they are consumed (from the end)

    def integral(self, value, lo, hi):
        rng = hi - lo
        nbytes = 0
        while nbytes < 8 and (rng >> (8 * nbytes)) > 0:
            nbytes += 1
        raw = value - lo
        self.tail += list(raw.to_bytes(nbytes, "big"))

    def boolean(self, b):
        self.tail.append(1 if b else 0)

    def string(self, s):
        self.front += s.replace(b"\\", b"\\\\") + b"\\n"  # a backslash and a non-backslash ends it

    # AnyValue(p, limit): 0 raw bits, 1 special (unused here), 4 small integer -3..3
    def value(self, v):
        if isinstance(v, int) and -3 <= v <= 3:
            self.integral(4, 0, 4)
            self.integral(v, -3, 3)
        else:
            self.integral(0, 0, 4)
            self.integral(struct.unpack("<Q", struct.pack("<d", v))[0], 0, 2**64 - 1)

    def header(self, nq, forces_before=(1.0, -2.0)):
        self.integral(nq - 9, 0, F3R_MAX_Q - 9)
        for _ in range(3):
            self.integral(0, 0, 3)          # default limits: 1000 N, 100 N m, 1000 N
        self.integral(len(forces_before), 0, 80)
        for f in forces_before:
            self.value(f)

    def bytes(self):
        return self.front + bytes(reversed(self.tail))


def effort_command(nq, legs, cylinders, platform, modal):
    s = Seed()
    s.header(nq)
    s.integral(0, 0, 2)
    for i in range(3):
        s.value(legs[i]); s.value(cylinders[i]); s.value(platform[i])
    s.integral(2, 0, 3)
    s.integral(len(modal), 0, 100)
    for m in modal:
        s.value(m)
    return s.bytes()


def effort_group(nq, data):
    s = Seed()
    s.header(nq)
    s.integral(1, 0, 2)
    s.boolean(False)
    s.integral(len(data), 0, 100)
    for d in data:
        s.value(d)
    s.boolean(False)
    return s.bytes()


def wrench(nq, frame, phi_p, force, torque):
    s = Seed()
    s.header(nq)
    s.integral(2, 0, 2)
    s.integral(3, 0, 3)
    s.string(frame)
    s.integral(7, 0, 2**32 - 1)             # header.seq
    s.boolean(True)                         # ~world_frame "world"
    s.boolean(True)                         # platform frame "platform"
    s.value(phi_p)
    s.value(force[0]); s.value(force[1])
    for v in (force[2], torque[0], torque[1]):
        if v == 0:
            s.boolean(True)
        else:
            s.boolean(False); s.value(v)
    s.value(torque[2])
    return s.bytes()


SEEDS = {
    "command_valid_rigid": effort_command(9, [5.0, 0, 0], [0.1, 0, -0.1], [0, 1.5, 0.01], []),
    "command_valid_modal": effort_command(18, [1, 2, 3], [0, 0, 0], [0, 0, 0], [0.5] * 9),
    "command_nan_leg": effort_command(9, [math.nan, 0, 0], [0, 0, 0], [0, 0, 0], []),
    "command_modal_wrong_length": effort_command(18, [0, 0, 0], [0, 0, 0], [0, 0, 0], [1.0, 2.0]),
    "command_above_limit": effort_command(9, [1000.0000000000001, 0, 0], [0, 0, 0], [0, 0, 0], []),
    "group_valid": effort_group(9, [5.0, 0, 0, 0.3, -0.2, 0.1]),
    "group_five_values": effort_group(9, [1.0] * 5),
    "group_inf_torque": effort_group(12, [0, 0, 0, 0, math.inf, 0]),
    "wrench_world": wrench(9, b"world", 0.0, (-4.33, 2.5, 0), (0, 0, 0.2)),
    "wrench_platform_turned": wrench(9, b"platform", 0.7, (3.0, -1.0, 0), (0, 0, 0)),
    "wrench_unknown_frame": wrench(9, b"moon", 0.0, (1.0, 0, 0), (0, 0, 0)),
    "wrench_out_of_plane": wrench(9, b"", 0.0, (0, 0, 1.0), (0, 0, 0)),
}

if __name__ == "__main__":
    os.makedirs(OUT, exist_ok=True)
    for name, data in SEEDS.items():
        with open(os.path.join(OUT, name), "wb") as f:
            f.write(data)
    print("wrote %d seeds to %s" % (len(SEEDS), OUT))
