#!/usr/bin/env python3
"""test_sqlite_affect.py — tests of the sqlite_affect package against the built module.

    SQLITE_AFFECT_PATH=build/affect.so PYTHONPATH=python /usr/bin/python3 \
        python/tests/test_sqlite_affect.py [FIXTURES_DIR]

(ctest: python/sqlite_affect from the checkout, python/pip-install from a venv.) Checks load()
and its search order and errors; to_numpy against the module's own reading of the same BLOBs
(motion_to_json, motion_points), for versions 1 and 2 and the fixtures; that to_numpy refuses
exactly the BLOBs the C decoder refuses (truncated, lengthened, bit-flipped copies); from_numpy
giving the module's bytes; the vector helpers on laban_vector. Uses the standard library's
unittest. Without NumPy the NumPy tests are skipped and the script exits with 77 (ctest: skipped)
after the others pass.
"""
import json
import os
import random
import sqlite3
import struct
import sys
import unittest

import sqlite_affect

try:
    import numpy as np
except ImportError:
    np = None

HERE = os.path.dirname(os.path.abspath(__file__))
FIXTURES = os.path.join(HERE, os.pardir, os.pardir, "tests", "fixtures")
NO_NUMPY = "NumPy is not installed (apt-get install python3-numpy)"


def connect():
    conn = sqlite3.connect(":memory:")
    sqlite_affect.load(conn)
    return conn


class FakeConnection:
    """A connection of a sqlite3 module built without extension loading (pyenv, macOS)."""

    def execute(self, *args):
        raise AssertionError("not reached")


class LoadTest(unittest.TestCase):
    def test_load_registers_the_functions(self):
        conn = sqlite3.connect(":memory:")
        name = sqlite_affect.load(conn)
        self.assertTrue(name)
        version = conn.execute("SELECT affect_version()").fetchone()[0]
        self.assertEqual(version, sqlite_affect.__version__)
        # loading is switched off again afterwards
        with self.assertRaises(sqlite3.OperationalError):
            conn.execute("SELECT load_extension('x')").fetchone()

    def test_explicit_path_that_does_not_load(self):
        conn = sqlite3.connect(":memory:")
        with self.assertRaises(sqlite_affect.LoadError) as cm:
            sqlite_affect.load(conn, "/nonexistent/affect.so")
        msg = str(cm.exception)
        self.assertIn("/nonexistent/affect.so (path argument)", msg)
        self.assertIn("SQLITE_AFFECT_PATH", msg)

    def test_search_order(self):
        saved = os.environ.get(sqlite_affect.ENV_VAR)
        try:
            self.assertEqual(sqlite_affect.module_path("/x/affect"), "/x/affect")
            os.environ[sqlite_affect.ENV_VAR] = "/from/env/affect.so"
            self.assertEqual(sqlite_affect.module_path(), "/from/env/affect.so")
            del os.environ[sqlite_affect.ENV_VAR]
            pkg = os.path.dirname(sqlite_affect.__file__)
            build = os.path.normpath(os.path.join(pkg, os.pardir, os.pardir, "build", "affect.so"))
            if os.path.isfile(os.path.join(pkg, "affect.so")):
                expected = os.path.join(pkg, "affect.so")
            elif os.path.isfile(build):
                expected = build
            else:
                expected = "affect"
            self.assertEqual(sqlite_affect.module_path(), expected)
        finally:
            if saved is None:
                os.environ.pop(sqlite_affect.ENV_VAR, None)
            else:
                os.environ[sqlite_affect.ENV_VAR] = saved

    def test_python_without_extension_loading(self):
        with self.assertRaises(sqlite_affect.LoadError) as cm:
            sqlite_affect.load(FakeConnection())
        msg = str(cm.exception)
        for what in ("cannot load extensions", "/usr/bin/python3",
                     "--enable-loadable-sqlite-extensions", "sqlean", "apsw"):
            self.assertIn(what, msg)


@unittest.skipIf(np is None, NO_NUMPY)
class MotionTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.conn = connect()

    def sql(self, query, *args):
        return self.conn.execute(query, args).fetchone()[0]

    def assert_matches_module(self, blob):
        """to_numpy(blob) says what the module says of the same BLOB."""
        pos, meta = sqlite_affect.to_numpy(blob)
        ref = json.loads(self.sql("SELECT motion_to_json(?)", blob))
        self.assertEqual(pos.dtype, np.float32)
        self.assertEqual(pos.shape, (len(ref["frames"]), len(ref["joints"]), 3))
        self.assertEqual(meta["names"], ref["joints"])
        self.assertEqual(meta["parents"], ref["parents"])
        self.assertEqual(meta["fps"], ref["fps"])
        self.assertEqual(meta["unit"], ref.get("unit", ""))
        # motion_to_json writes the shortest text that reads back as the same float32
        np.testing.assert_array_equal(pos, np.array(ref["frames"], dtype=np.float32))
        # and motion_points, one row per frame and joint, as float64 of the stored float32
        rows = self.conn.execute("SELECT frame, joint, x, y, z FROM motion_points(?)",
                                 (blob,)).fetchall()
        pts = np.array([r[2:] for r in rows], dtype=np.float64)
        np.testing.assert_array_equal(pts.reshape(pos.shape), pos.astype(np.float64))
        return pos, meta

    def test_version_1(self):
        blob = self.sql("SELECT motion_synth('knock', 'angry', 3)")
        pos, meta = self.assert_matches_module(blob)
        self.assertEqual(meta["version"], 1)
        self.assertIsNone(meta["skeleton"])
        self.assertIsNone(meta["rotations"])
        self.assertEqual(meta["unit"], "m")

    def test_version_2_with_rotations(self):
        blob = self.sql("SELECT motion_from_bvh(motion_to_bvh(motion_synth('walk', 'sad', 2)))")
        pos, meta = self.assert_matches_module(blob)
        self.assertEqual(meta["version"], 2)
        T, J = pos.shape[:2]
        self.assertEqual(meta["rotations"].shape, (T, J, 4))
        self.assertEqual(meta["translations"].shape, (T, J, 3))
        norms = np.linalg.norm(meta["rotations"].astype(np.float64), axis=2)
        self.assertLess(np.abs(norms - 1).max(), 1e-3)
        root = meta["parents"].index(-1)
        self.assertEqual(meta["skeleton"][root]["channels"][:3],
                         ["Xposition", "Yposition", "Zposition"])
        # the root's position channels are its translations, and its world position
        np.testing.assert_allclose(meta["translations"][:, root, :], pos[:, root, :],
                                   atol=1e-4)
        # joints without position channels translate by their rest offset in every frame
        child = next(j for j, s in enumerate(meta["skeleton"])
                     if not any(c.endswith("position") for c in s["channels"]))
        np.testing.assert_array_equal(
            meta["translations"][:, child, :],
            np.tile(np.float32(meta["skeleton"][child]["offset"]), (T, 1)))
        rot = self.conn.execute(
            "SELECT qw, qx, qy, qz FROM motion_angles(?) WHERE frame = 5 AND joint = ?",
            (blob, child)).fetchone()
        if rot is not None:
            np.testing.assert_allclose(meta["rotations"][5, child], rot, atol=1e-6)

    def test_fixtures(self):
        for name, version in (("motion-v1.bin", 1), ("motion-v2.bin", 2)):
            with open(os.path.join(FIXTURES, name), "rb") as f:
                blob = f.read()
            with self.subTest(fixture=name):
                _, meta = self.assert_matches_module(blob)
                self.assertEqual(meta["version"], version)

    def test_refuses_what_the_module_refuses(self):
        """Truncated, lengthened and bit-flipped copies: to_numpy raises ValueError exactly when
        the module's decoder gives an error."""
        blobs = [self.sql("SELECT motion_slice(motion_synth('wave', 'happy', 1), 0, 3)"),
                 self.sql("SELECT motion_slice(motion_from_bvh(motion_to_bvh("
                          "motion_synth('bow', 'sad', 1))), 0, 2)")]
        for name in ("motion-v1.bin", "motion-v2.bin"):
            with open(os.path.join(FIXTURES, name), "rb") as f:
                blobs.append(f.read())
        rng = random.Random(17)
        counts = {"agree_ok": 0, "agree_error": 0}
        for blob in blobs:
            variants = [blob[:n] for n in range(0, len(blob), max(1, len(blob) // 97))]
            variants += [blob + b"\0", blob + bytes(rng.randrange(256) for _ in range(13))]
            for _ in range(400):
                b = bytearray(blob)
                for _ in range(rng.choice((1, 1, 2, 3))):
                    i = rng.randrange(len(b))
                    b[i] ^= 1 << rng.randrange(8)
                variants.append(bytes(b))
            for _ in range(100):  # header fields set to edge values
                b = bytearray(blob)
                i = rng.randrange(4, 32)
                b[i] = rng.choice((0, 1, 2, 3, 0x7f, 0x80, 0xff))
                variants.append(bytes(b))
            for v in variants:
                try:
                    self.conn.execute("SELECT motion_info(?)", (v,)).fetchone()
                    module_error = None
                except sqlite3.Error as e:
                    module_error = str(e)
                try:
                    sqlite_affect.to_numpy(v)
                    ours = None
                except ValueError as e:
                    ours = str(e)
                self.assertEqual(ours is None, module_error is None,
                                 f"module: {module_error!r}; to_numpy: {ours!r}; blob {v.hex()}")
                counts["agree_ok" if ours is None else "agree_error"] += 1
        self.assertGreater(counts["agree_error"], 1000)
        self.assertGreater(counts["agree_ok"], 10)
        print(f"\nto_numpy and motion_info agree on {sum(counts.values())} BLOBs "
              f"({counts['agree_ok']} valid, {counts['agree_error']} refused)", file=sys.stderr)

    def test_error_messages(self):
        blob = self.sql("SELECT motion_synth('knock', 'sad', 1)")
        cases = [
            (blob[:20], "to_numpy: not a valid motion: truncated: 20 bytes is shorter than the "
                        "32-byte header"),
            (b"XXXX" + blob[4:], "to_numpy: not a valid motion: not a motion (bad magic bytes "
                                 "at offset 0)"),
            (blob[:4] + b"\x03\x00" + blob[6:], "to_numpy: not a valid motion: unknown format "
                                                "version 3 (this module reads 1 .. 2)"),
            (blob[:-1], "to_numpy: not a valid motion: truncated: %d bytes, expected %d for"
                        % (len(blob) - 1, len(blob))),
            (blob + b"\0", "to_numpy: not a valid motion: trailing bytes: %d bytes, expected %d"
                           % (len(blob) + 1, len(blob))),
            (blob[:-4] + struct.pack("<f", float("nan")),
             "to_numpy: not a valid motion: non-finite coordinate at frame"),
        ]
        for data, message in cases:
            with self.subTest(message=message):
                with self.assertRaises(ValueError) as cm:
                    sqlite_affect.to_numpy(data)
                self.assertTrue(str(cm.exception).startswith(message), str(cm.exception))
        with self.assertRaises(TypeError):
            sqlite_affect.to_numpy("AFMO")
        with self.assertRaises(TypeError):
            sqlite_affect.to_numpy(None)

    def test_from_numpy_gives_the_module_bytes(self):
        blob = self.sql("SELECT motion_synth('bow', 'happy', 4)")
        pos, meta = sqlite_affect.to_numpy(blob)
        again = sqlite_affect.from_numpy(pos, meta["names"], meta["parents"], fps=meta["fps"],
                                         unit=meta["unit"])
        self.assertEqual(again, blob)
        # from float64 and lists too; motion_from_json makes the same bytes
        text = json.dumps({"fps": 25, "unit": "cm", "joints": ["Hips", "Spine", "Head"],
                           "parents": [-1, 0, 1],
                           "frames": [[[0, 90.5, 1], [0, 110, 1.25], [0, 160, 2]],
                                      [[0.5, 90, 1], [0.5, 110, 1], [0.5, 161, 2.5]]]})
        ref = self.sql("SELECT motion_from_json(?)", text)
        d = json.loads(text)
        ours = sqlite_affect.from_numpy(np.array(d["frames"], dtype=np.float64), d["joints"],
                                        d["parents"], fps=25, unit="cm")
        self.assertEqual(ours, ref)
        self.assertEqual(self.sql("SELECT motion_joints(?)", ours), 3)
        # a motion with no unit and no parents given
        ours = sqlite_affect.from_numpy([[[1, 2, 3]]], ["a"])
        self.assertEqual(json.loads(self.sql("SELECT motion_info(?)", ours))["joints"], 1)

    def test_from_numpy_refuses_bad_input(self):
        ok = np.zeros((2, 2, 3), dtype=np.float32)
        cases = [
            (dict(positions=np.zeros((2, 6))), "from_numpy: positions must have the shape"),
            (dict(positions=np.zeros((0, 2, 3))), "from_numpy: frame count 0 out of range"),
            (dict(names=["a"]), "from_numpy: names must be a list of 2 joint names"),
            (dict(names=["a", "a"]), 'from_numpy: joints 0 and 1 have the same name "a"'),
            (dict(names=["a", ""]), "from_numpy: joint 1: name length 0 out of range"),
            (dict(names=["a", "b\0"]), "from_numpy: joint 1: name contains a NUL"),
            (dict(names=["a", "\udcff"]), "from_numpy: joint 1: name is not valid UTF-8"),
            (dict(parents=[1, 0]), "from_numpy: joint 0: parent indices form a cycle"),
            (dict(parents=[-1, 2]), "from_numpy: joint 1: parent index 2 out of range"),
            (dict(parents=[-1]), "from_numpy: parents must have 2 entries"),
            (dict(fps=0), "from_numpy: frames per second 0.0 out of range"),
            (dict(fps=float("nan")), "from_numpy: frames per second nan out of range"),
            (dict(unit="m/s"), "from_numpy: unit must be at most 15 letters"),
            (dict(positions=np.full((2, 2, 3), 1e39)), "from_numpy: non-finite coordinate (or "
                                                       "beyond float32) at frame 0, joint 0, x"),
            (dict(positions=np.array([[["a", "b", "c"]]])), "from_numpy: positions must be real"),
        ]
        for change, message in cases:
            args = dict(positions=ok, names=["a", "b"], parents=None, fps=30, unit="")
            args.update(change)
            with self.subTest(message=message):
                with self.assertRaises(ValueError) as cm:
                    sqlite_affect.from_numpy(**args)
                self.assertTrue(str(cm.exception).startswith(message), str(cm.exception))

    def test_vectors(self):
        blob = self.sql("SELECT laban_vector(motion_synth('knock', 'happy', 2))")
        vec = sqlite_affect.vector_to_numpy(blob)
        self.assertEqual(vec.dtype, np.float32)
        self.assertEqual(vec.shape, (27,))
        names = json.loads(self.sql("SELECT laban_names()"))
        weight = self.sql("SELECT laban_weight(motion_synth('knock', 'happy', 2))")
        self.assertEqual(len(names), 27)
        self.assertIn(np.float32(weight), vec)  # one component is the Weight
        self.assertEqual(sqlite_affect.numpy_to_vector(vec), blob)
        self.assertEqual(sqlite_affect.numpy_to_vector([1.5, float("nan")]),
                         struct.pack("<ff", 1.5, float("nan")))
        for bad in (b"", b"abc", b"abcde"):
            with self.assertRaises(ValueError):
                sqlite_affect.vector_to_numpy(bad)
        for bad in ([], [[1.0]], [float("inf")], [1e39], ["x"]):
            with self.assertRaises(ValueError):
                sqlite_affect.numpy_to_vector(bad)


if __name__ == "__main__":
    if len(sys.argv) > 1 and os.path.isdir(sys.argv[1]):
        FIXTURES = sys.argv.pop(1)
    result = unittest.main(exit=False, verbosity=1).result
    if not result.wasSuccessful():
        sys.exit(1)
    if np is None:
        print(f"SKIP: the NumPy tests ({NO_NUMPY})")
        sys.exit(77)
