"""sqlite_affect — the sqlite-affect SQLite extension from Python.

    import sqlite3, sqlite_affect
    conn = sqlite3.connect("demo.db")
    sqlite_affect.load(conn)                     # registers motion_*, laban_*, hmm_*, affect_*
    blob = conn.execute("SELECT motion FROM motions LIMIT 1").fetchone()[0]
    positions, meta = sqlite_affect.to_numpy(blob)     # (frames, joints, 3) float32, metadata
    again = sqlite_affect.from_numpy(positions, meta["names"], meta["parents"],
                                     fps=meta["fps"], unit=meta["unit"])
    vec = sqlite_affect.vector_to_numpy(conn.execute(
        "SELECT laban_vector(motion) FROM motions LIMIT 1").fetchone()[0])   # 27 float32

load() finds the module (affect.so) in this order: the path given, the environment variable
SQLITE_AFFECT_PATH, this package's own directory, the build tree of the checkout this package
lives in (python/../build), then the bare name "affect", which SQLite resolves through the
dynamic loader (an install with `cmake --install build`, or LD_LIBRARY_PATH). A Python whose
sqlite3 module cannot load extensions (pyenv's default builds, python.org's macOS installers)
gets a LoadError that says what to use instead.

to_numpy() and from_numpy() read and write the motion BLOB themselves, following
docs/FORMATS.md (versions 1 and 2), and check a BLOB as the C decoder does: a malformed one is a
ValueError naming what is wrong and where. The vector helpers convert the plain float32 BLOBs
(laban_vector, the `laban` index's vectors: sqlite-vec's format). They need NumPy; load() does
not.
"""
import math
import os
import struct

__version__ = "0.1.0"
__all__ = ["load", "module_path", "LoadError", "to_numpy", "from_numpy", "vector_to_numpy",
           "numpy_to_vector", "__version__"]

ENV_VAR = "SQLITE_AFFECT_PATH"
_HERE = os.path.dirname(os.path.abspath(__file__))

# the motion BLOB (docs/FORMATS.md; core/include/affect/motion.h)
_MAGIC = b"AFMO"
_HEADER = 32
_NEWEST_VERSION = 2
_FLAG_SKELETON = 1
_FLAG_ROTATIONS = 2
_MAX_FRAMES = 16777216
_MAX_JOINTS = 4096
_MAX_NAME = 1024
_MAX_UNIT = 15
_MAX_FPS = 100000.0
_JOINT_SIZE = 32
_QUAT_NORM_TOL = 1e-3
_END_SITE = 1
_UNIT_CHARS = frozenset(b"abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_.-")
_CHANNELS = ("Xposition", "Yposition", "Zposition", "Xrotation", "Yrotation", "Zrotation")

_NO_LOADING = (
    "sqlite_affect.load: this Python's sqlite3 module cannot load extensions: it was built without "
    "SQLITE_ENABLE_LOAD_EXTENSION ({exe}; pyenv's default builds and python.org's macOS "
    "installers are like this). Use a Python that can: Debian's /usr/bin/python3 (apt-get install "
    "python3), or rebuild this one with PYTHON_CONFIGURE_OPTS=--enable-loadable-sqlite-extensions "
    "(pyenv install --force <version>; ./configure --enable-loadable-sqlite-extensions); or use "
    "the sqlean.py package (import sqlean as sqlite3) or apsw, whose connections can load "
    "extensions; or the sqlite3 shell: sqlite3 -cmd '.load affect'")


class LoadError(RuntimeError):
    """The module could not be loaded into the connection (the message says why and what to do)."""


def _candidates(path):
    """(where the name came from, name to give SQLite) in the order load() tries them."""
    if path is not None:
        return [("path argument", os.fspath(path))]
    env = os.environ.get(ENV_VAR)
    if env:
        return [(ENV_VAR, env)]
    found = []
    for origin, folder in (("package directory", _HERE),
                           ("build tree", os.path.join(_HERE, os.pardir, os.pardir, "build"))):
        lib = os.path.join(folder, "affect.so")
        if os.path.isfile(lib):
            found.append((origin, os.path.normpath(lib)))
    found.append(("installed (dynamic loader)", "affect"))
    return found


def module_path(path=None):
    """The name load() would try first: the path given, $SQLITE_AFFECT_PATH, the module in this
    package's directory or in the checkout's build tree, else "affect" (the installed one)."""
    return _candidates(path)[0][1]


def load(conn, path=None):
    """Loads sqlite-affect into conn (a sqlite3.Connection) and returns the name it loaded.

    path: the module (build/affect or build/affect.so); without it, $SQLITE_AFFECT_PATH, then
    this package's directory, the checkout's build tree and finally the installed "affect".
    Extension loading is switched on only for the call. Raises LoadError when this Python cannot
    load extensions or when no candidate loads (the message lists each attempt)."""
    if not hasattr(conn, "enable_load_extension") or not hasattr(conn, "load_extension"):
        import sys
        raise LoadError(_NO_LOADING.format(exe=sys.executable))
    tried = []
    conn.enable_load_extension(True)
    try:
        for origin, name in _candidates(path):
            try:
                conn.load_extension(name)
                return name
            except Exception as e:  # sqlite3.OperationalError; another driver's own error
                tried.append(f"{name} ({origin}): {e}")
    finally:
        conn.enable_load_extension(False)
    raise LoadError(
        "sqlite_affect.load: cannot load the sqlite-affect module; tried " + "; ".join(tried) +
        ". Build it (cmake -S . -B build && cmake --build build) and pass its path, set " +
        ENV_VAR + "=/path/to/affect.so, or install it (cmake --install build; for a prefix "
        "outside the loader's search path set LD_LIBRARY_PATH to its lib directory)")


def _numpy():
    try:
        import numpy
    except ImportError as e:
        raise ImportError("sqlite_affect: to_numpy, from_numpy and the vector helpers need NumPy "
                          "(apt-get install python3-numpy, or pip install numpy)") from e
    return numpy


def _bytes(blob, fn):
    if isinstance(blob, (bytes, bytearray, memoryview)):
        return bytes(blob)
    raise TypeError(f"{fn}: expected a BLOB (bytes), got {type(blob).__name__}")


def _check_parents(parents, fn):
    n = len(parents)
    for j, p in enumerate(parents):
        if p < -1 or p >= n:
            raise ValueError(f"{fn}: joint {j}: parent index {p} out of range (-1 .. {n - 1})")
        if p == j:
            raise ValueError(f"{fn}: joint {j}: is its own parent")
    for j in range(n):
        p, steps = parents[j], 0
        while p >= 0 and steps <= n:
            p, steps = parents[p], steps + 1
        if p >= 0:
            raise ValueError(f"{fn}: joint {j}: parent indices form a cycle")


def _check_name(raw, j, fn):
    """The text of a joint name given as bytes, or ValueError."""
    if b"\0" in raw:
        raise ValueError(f"{fn}: joint {j}: name contains a NUL byte")
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as e:
        raise ValueError(f"{fn}: joint {j}: name is not valid UTF-8 "
                         f"(byte 0x{raw[e.start]:02x} at offset {e.start})") from None


def to_numpy(blob):
    """Decodes a motion BLOB into (positions, meta).

    positions: float32 array of shape (frames, joints, 3) (x, y, z in the motion's unit).
    meta: {"names": [str], "parents": [int] (-1 for a root), "fps": float, "unit": str ("" when
    unknown), "version": 1 or 2, "skeleton": None or one dict per joint {"offset": (x, y, z),
    "channels": [BVH channel names], "end_site": bool}, "rotations": None or a float32 array
    (frames, joints, 4) of local unit quaternions (w, x, y, z), "translations": None or a float32
    array (frames, joints, 3) of local translations (the position channels' values, else the
    offset)}. Raises ValueError for a malformed BLOB, TypeError for something else than bytes."""
    np = _numpy()
    fn = "to_numpy"
    data = _bytes(blob, fn)
    size = len(data)
    bad = f"{fn}: not a valid motion: "
    if size < _HEADER:
        raise ValueError(f"{bad}truncated: {size} bytes is shorter than the {_HEADER}-byte header")
    if data[:4] != _MAGIC:
        raise ValueError(f"{bad}not a motion (bad magic bytes at offset 0)")
    version, flags, frames, joints, fps = struct.unpack_from("<HHIId", data, 4)
    if version < 1 or version > _NEWEST_VERSION:
        raise ValueError(f"{bad}unknown format version {version} "
                         f"(this module reads 1 .. {_NEWEST_VERSION})")
    if (flags != 0) if version == 1 else \
            (flags & ~(_FLAG_SKELETON | _FLAG_ROTATIONS) or not flags & _FLAG_SKELETON):
        raise ValueError(f"{bad}unknown flags 0x{flags:04x} (offset 6)")
    if not 1 <= frames <= _MAX_FRAMES:
        raise ValueError(f"{bad}frame count {frames} out of range (1 .. {_MAX_FRAMES}) (header)")
    if not 1 <= joints <= _MAX_JOINTS:
        raise ValueError(f"{bad}joint count {joints} out of range (1 .. {_MAX_JOINTS}) (header)")
    if not 0.0 < fps <= _MAX_FPS:  # also refuses NaN
        raise ValueError(f"{bad}frames per second {fps} out of range (0 .. {_MAX_FPS:g}] (header)")
    for i in range(25, 32):
        if data[i]:
            raise ValueError(f"{bad}reserved header byte {i} is not zero")
    unit_len = data[24]
    off = _HEADER
    if unit_len > _MAX_UNIT or size - off < unit_len:
        raise ValueError(f"{bad}truncated or bad unit (length {unit_len} at offset 24)")
    unit_raw = data[off:off + unit_len]
    for i, c in enumerate(unit_raw):
        if c not in _UNIT_CHARS:
            raise ValueError(f"{bad}unit has a character other than letters, digits, '_', '.', "
                             f"'-' (byte {i})")
    off += unit_len
    raw_names = []
    for j in range(joints):
        if size - off < 2:
            raise ValueError(f"{bad}truncated in the name of joint {j} (offset {off})")
        n = struct.unpack_from("<H", data, off)[0]
        if not 1 <= n <= _MAX_NAME:
            raise ValueError(f"{bad}joint {j}: name length {n} out of range (1 .. {_MAX_NAME}) "
                             f"at offset {off}")
        if size - off - 2 < n:
            raise ValueError(f"{bad}truncated in the name of joint {j} (offset {off})")
        raw_names.append(data[off + 2:off + 2 + n])
        off += 2 + n
    parents_off = off
    pos_off = parents_off + 4 * joints
    expect = pos_off + 12 * frames * joints
    skel_off = expect
    translated = []
    if flags & _FLAG_SKELETON:
        if size < skel_off or size - skel_off < joints * _JOINT_SIZE:
            raise ValueError(f"{bad}truncated: {size} bytes, the skeleton part needs "
                             f"{joints * _JOINT_SIZE} from offset {skel_off}")
        for j in range(joints):
            q = skel_off + j * _JOINT_SIZE
            count = min(data[q + 24], 6)
            translated.append(any(data[q + 25 + c] <= 2 for c in range(count)))
        expect += joints * _JOINT_SIZE
        if flags & _FLAG_ROTATIONS:
            expect += frames * (joints * 16 + sum(translated) * 12)
    if size != expect:
        what = "truncated" if size < expect else "trailing bytes"
        raise ValueError(f"{bad}{what}: {size} bytes, "
                         f"expected {expect} for {frames} frames x {joints} joints")

    names = [_check_name(raw, j, bad.rstrip(": ")) for j, raw in enumerate(raw_names)]
    seen = {}
    for j, name in enumerate(names):
        if name in seen:
            raise ValueError(f'{bad}joints {seen[name]} and {j} have the same name "{name[:64]}"')
        seen[name] = j
    parents = list(struct.unpack_from(f"<{joints}i", data, parents_off))
    _check_parents(parents, bad.rstrip(": "))
    pos = np.frombuffer(data, dtype="<f4", count=frames * joints * 3, offset=pos_off)
    finite = np.isfinite(pos)
    if not finite.all():
        i = int(np.argmin(finite))
        fj = i // 3
        raise ValueError(f"{bad}non-finite coordinate at frame {fj // joints}, joint "
                         f"{fj % joints} ({names[fj % joints][:64]}), {'xyz'[i % 3]}")
    positions = pos.astype(np.float32).reshape(frames, joints, 3)  # a native, writable copy

    skeleton = rotations = translations = None
    if flags & _FLAG_SKELETON:
        skeleton = []
        has_child = [False] * joints
        for p in parents:
            if p >= 0:
                has_child[p] = True
        for j in range(joints):
            q = skel_off + j * _JOINT_SIZE
            offset = struct.unpack_from("<3d", data, q)
            count, kinds, jflags = data[q + 24], data[q + 25:q + 31], data[q + 31]
            label = f"joint {j} ({names[j][:64]})"
            for c in range(count, 6):
                if kinds[c]:
                    raise ValueError(f"{bad}joint {j}: unused channel byte {c} is not zero "
                                     f"(offset {q + 25 + c})")
            if count > 6:
                raise ValueError(f"{bad}{label}: {count} channels (at most 6)")
            for c in range(count):
                if kinds[c] >= len(_CHANNELS):
                    raise ValueError(f"{bad}{label}: channel type {kinds[c]} unknown")
                if kinds[c] in kinds[:c]:
                    raise ValueError(f"{bad}{label}: channel {_CHANNELS[kinds[c]]} listed twice")
            if jflags & ~_END_SITE:
                raise ValueError(f"{bad}{label}: unknown joint flags 0x{jflags:02x}")
            if jflags & _END_SITE:
                if count or parents[j] < 0:
                    raise ValueError(f"{bad}{label}: an End Site must have a parent and no "
                                     "channels")
                if has_child[j]:
                    raise ValueError(f"{bad}{label}: an End Site cannot have children")
            if not all(math.isfinite(v) for v in offset):
                raise ValueError(f"{bad}{label}: non-finite offset")
            skeleton.append({"offset": offset, "channels": [_CHANNELS[k] for k in kinds[:count]],
                             "end_site": bool(jflags & _END_SITE)})
    if flags & _FLAG_ROTATIONS:
        rot_off = skel_off + joints * _JOINT_SIZE
        rotations = np.frombuffer(data, dtype="<f4", count=frames * joints * 4, offset=rot_off)
        rotations = rotations.astype(np.float32).reshape(frames, joints, 4)
        moving = [j for j in range(joints) if translated[j]]
        translations = np.empty((frames, joints, 3), dtype=np.float32)
        with np.errstate(over="ignore"):  # an offset beyond float32 is refused below
            for j in range(joints):
                translations[:, j, :] = np.array(skeleton[j]["offset"]).astype(np.float32)
        if moving:
            stored = np.frombuffer(data, dtype="<f4", count=frames * len(moving) * 3,
                                   offset=rot_off + frames * joints * 16)
            translations[:, moving, :] = stored.reshape(frames, len(moving), 3)
        norms = np.sqrt((rotations.astype(np.float64) ** 2).sum(axis=2))
        ok_rot = np.isfinite(rotations).all(axis=2)
        ok_trans = np.isfinite(translations).all(axis=2)
        ok = ok_rot & ok_trans & (np.abs(norms - 1) <= _QUAT_NORM_TOL)
        if not ok.all():
            i = int(np.argmin(ok.reshape(-1)))
            t, j = divmod(i, joints)
            where = f"frame {t}, joint {j} ({names[j][:64]})"
            if not ok_rot[t, j]:
                raise ValueError(f"{bad}non-finite rotation at {where}")
            if not ok_trans[t, j]:
                raise ValueError(f"{bad}non-finite translation at {where}")
            raise ValueError(f"{bad}rotation at {where} is not a unit quaternion "
                             f"(norm {norms[t, j]:g})")
    meta = {"names": names, "parents": parents, "fps": fps, "unit": unit_raw.decode("ascii"),
            "version": version, "skeleton": skeleton, "rotations": rotations,
            "translations": translations}
    return positions, meta


def from_numpy(positions, names, parents=None, fps=30.0, unit=""):
    """Encodes positions (array-like of shape (frames, joints, 3), finite) as a motion BLOB
    (version 1: positions, names, parents, fps, unit; no skeleton), the bytes the module's own
    encoder writes for the same motion (motion_from_json gives identical bytes).

    names: one str per joint (unique, 1 .. 1024 bytes of UTF-8, no NUL); parents: one int per
    joint, -1 for a root (default: all -1), without cycles; fps in (0, 100000]; unit: up to 15
    letters, digits, '_', '.', '-' ("" = unknown). Raises ValueError for anything the decoder
    would refuse."""
    np = _numpy()
    fn = "from_numpy"
    arr = np.asarray(positions)
    if arr.ndim != 3 or arr.shape[2] != 3:
        raise ValueError(f"{fn}: positions must have the shape (frames, joints, 3), got "
                         f"{arr.shape}")
    frames, joints = arr.shape[0], arr.shape[1]
    if not 1 <= frames <= _MAX_FRAMES:
        raise ValueError(f"{fn}: frame count {frames} out of range (1 .. {_MAX_FRAMES})")
    if not 1 <= joints <= _MAX_JOINTS:
        raise ValueError(f"{fn}: joint count {joints} out of range (1 .. {_MAX_JOINTS})")
    if not np.issubdtype(arr.dtype, np.number) or np.iscomplexobj(arr):
        raise ValueError(f"{fn}: positions must be real numbers, got dtype {arr.dtype}")
    with np.errstate(over="ignore", invalid="ignore"):
        pos = arr.astype("<f4")
    finite = np.isfinite(pos)
    if not finite.all():
        i = int(np.argmin(finite.reshape(-1)))
        fj = i // 3
        raise ValueError(f"{fn}: non-finite coordinate (or beyond float32) at frame "
                         f"{fj // joints}, joint {fj % joints}, {'xyz'[i % 3]}")
    if isinstance(names, (str, bytes)) or len(names) != joints:
        raise ValueError(f"{fn}: names must be a list of {joints} joint names")
    encoded = []
    for j, name in enumerate(names):
        if not isinstance(name, str):
            raise ValueError(f"{fn}: joint {j}: name must be a str, got {type(name).__name__}")
        try:
            raw = name.encode("utf-8")
        except UnicodeEncodeError:
            raise ValueError(f"{fn}: joint {j}: name is not valid UTF-8 (a lone surrogate)") \
                from None
        if not 1 <= len(raw) <= _MAX_NAME:
            raise ValueError(f"{fn}: joint {j}: name length {len(raw)} out of range "
                             f"(1 .. {_MAX_NAME} bytes)")
        if b"\0" in raw:
            raise ValueError(f"{fn}: joint {j}: name contains a NUL character")
        encoded.append(raw)
    if len(set(encoded)) != joints:
        first = {}
        for j, raw in enumerate(encoded):
            if raw in first:
                raise ValueError(f'{fn}: joints {first[raw]} and {j} have the same name '
                                 f'"{names[j][:64]}"')
            first[raw] = j
    if parents is None:
        parents = [-1] * joints
    parents = [int(p) for p in parents]
    if len(parents) != joints:
        raise ValueError(f"{fn}: parents must have {joints} entries, got {len(parents)}")
    _check_parents(parents, fn)
    fps = float(fps)
    if not 0.0 < fps <= _MAX_FPS:
        raise ValueError(f"{fn}: frames per second {fps} out of range (0 .. {_MAX_FPS:g}]")
    unit_raw = unit.encode("ascii", "replace") if isinstance(unit, str) else b"?"
    if len(unit_raw) > _MAX_UNIT or any(c not in _UNIT_CHARS for c in unit_raw):
        raise ValueError(f"{fn}: unit must be at most {_MAX_UNIT} letters, digits, '_', '.', "
                         f"'-', got {unit!r}")
    out = bytearray(_MAGIC)
    out += struct.pack("<HHIId", 1, 0, frames, joints, fps)
    out += bytes([len(unit_raw)]) + bytes(7) + unit_raw
    for raw in encoded:
        out += struct.pack("<H", len(raw)) + raw
    out += struct.pack(f"<{joints}i", *parents)
    out += pos.tobytes()
    return bytes(out)


def vector_to_numpy(blob):
    """A float32 vector BLOB (laban_vector, the `laban` index, sqlite-vec) as a 1-D float32
    array; NaN marks a missing component. ValueError if its length is 0 or not a multiple of 4."""
    np = _numpy()
    data = _bytes(blob, "vector_to_numpy")
    if not data or len(data) % 4:
        raise ValueError(f"vector_to_numpy: a float32 vector BLOB has a length that is a positive "
                         f"multiple of 4 bytes, got {len(data)}")
    return np.frombuffer(data, dtype="<f4").astype(np.float32)


def numpy_to_vector(values):
    """A 1-D array-like of numbers as a float32 vector BLOB (little-endian, no header: the
    format of laban_vector and sqlite-vec). NaN is kept (a missing component); infinities and
    values beyond float32 are a ValueError."""
    np = _numpy()
    arr = np.asarray(values)
    if arr.ndim != 1 or arr.size == 0:
        raise ValueError(f"numpy_to_vector: expected a non-empty 1-D array, got shape {arr.shape}")
    if not np.issubdtype(arr.dtype, np.number) or np.iscomplexobj(arr):
        raise ValueError(f"numpy_to_vector: expected real numbers, got dtype {arr.dtype}")
    with np.errstate(over="ignore", invalid="ignore"):
        out = arr.astype("<f4")
    if np.isinf(out).any():
        i = int(np.argmax(np.isinf(out)))
        raise ValueError(f"numpy_to_vector: component {i} is infinite or beyond float32 "
                         f"({arr[i]!r})")
    return out.tobytes()
