#!/usr/bin/env python3
"""import_folder.py — import a folder of BVH files into a database, file by file, with progress.

    python3 examples/import_folder.py FOLDER [DB] [--unit cm] [--source NAME] [--module path/to/build/affect]

The Python twin of sql/import_bvh.sql: every .bvh file under FOLDER (sub-folders too, in name
order) goes into the `motions` table of DB (default: motions.db; sql/schema.sql is applied
first), labelled from names of the form dataset-1_{content}_{style}_{take}.bvh. A file that
does not import is skipped, not fatal: it is recorded in `import_errors` (file, line, message,
at) with the same message the shell script records, and the others are imported. One line per
file shows the progress:

    [1/4] mixed/dataset-1_wave_sad_001.bvh: 199 frames, 26 joints
    [2/4] mixed/garbage.bvh: skipped: motion_from_bvh: expected HIERARCHY, found GIF89a\\x01\\x00\\xff (mixed/garbage.bvh, line 1)
    [3/4] mixed/other.bvh: 2 frames, 1 joints
    [4/4] mixed/truncated.bvh: skipped: motion_from_bvh: expected 199 frames, found 194 (mixed/truncated.bvh, line 324)
    imported 2 of 4 BVH files from mixed; skipped 2 (recorded in import_errors)

Each file is parsed once, by motion_from_bvh with {"on_error": "null"} (NULL for a bad file);
only a bad file is parsed again, by motion_bvh_error, for its message. The work is committed
at least every second (and at the end), so an interrupted run keeps nearly all it did;
re-running replaces rows of the same name. The exit status is 0 when the folder was read,
whatever was skipped.
"""
import argparse
import json
import os
import re
import sqlite3
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))


def connect(db, module):
    conn = sqlite3.connect(db)
    if not hasattr(conn, "enable_load_extension"):
        sys.exit(
            "This Python's sqlite3 module cannot load extensions (built without "
            "SQLITE_ENABLE_LOAD_EXTENSION: pyenv's and python.org's macOS builds are like this).\n"
            "Use Debian's /usr/bin/python3, or a Python built with --enable-loadable-sqlite-extensions, "
            "or the sqlite3 shell and sql/import_bvh.sql.")
    conn.enable_load_extension(True)
    try:
        conn.load_extension(module)
    except sqlite3.OperationalError as e:
        sys.exit(f"cannot load {module}: {e}\nBuild it first: ./run.sh demo (or cmake -S . -B build && cmake --build build)")
    conn.enable_load_extension(False)
    return conn


def bvh_files(folder):
    """Paths of the regular .bvh files under folder, named as the shell's fsdir() names them."""
    found = []
    for root, dirs, files in os.walk(folder):
        dirs.sort()
        for name in files:
            path = os.path.join(root, name)
            if name.lower().endswith(".bvh") and os.path.isfile(path) and not os.path.islink(path):
                found.append(path)
    return sorted(found)


def labels(stem):
    """(content, emotion) from dataset-1_{content}_{style}_{take}, as sql/import_bvh.sql reads
    them; (None, None) for other names."""
    if not re.match(r"(?i)dataset-.*_.*_.*_", stem, re.S):
        return None, None
    parts = stem.split("_")
    return parts[1] or None, parts[2] or None


def record_error(conn, path, error):
    """Stores a skipped file in import_errors and returns its message."""
    line = None
    found = re.match(r"line (\d+): (.*)", error, re.S)
    if error == "cannot read the file":
        message = f"readfile: cannot read the file ({path})"
    elif found:
        line = int(found.group(1))
        message = f"motion_from_bvh: {found.group(2)} ({path}, line {line})"
    else:
        message = f"motion_from_bvh: {error} ({path})"
    conn.execute("INSERT OR REPLACE INTO import_errors(file, line, message) VALUES (?, ?, ?)",
                 (path, line, message))
    return message


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("folder")
    parser.add_argument("db", nargs="?", default="motions.db")
    parser.add_argument("--unit", help="unit recorded in each motion, e.g. cm")
    parser.add_argument("--source", help="the rows' source column (default: the folder)")
    parser.add_argument("--module", default=os.path.join(HERE, "..", "build", "affect"),
                        help="the built extension (default: build/affect)")
    args = parser.parse_args()
    if not os.path.isdir(args.folder):
        sys.exit(f"import_folder.py: {args.folder} is not a folder")

    conn = connect(args.db, args.module)
    with open(os.path.join(HERE, "..", "sql", "schema.sql"), encoding="utf-8") as f:
        conn.executescript(f.read())
    options = {"unit": args.unit} if args.unit else {}
    check = json.dumps(options) if options else None       # for motion_bvh_error
    lenient = json.dumps({**options, "on_error": "null"})  # for motion_from_bvh
    source = args.source or args.folder

    paths = bvh_files(args.folder)
    imported = 0
    committed = time.monotonic()
    for i, path in enumerate(paths, 1):
        try:
            with open(path, "rb") as f:
                data = f.read()
        except OSError:
            data = None
        m = None
        if data is not None:
            (m,) = conn.execute("SELECT motion_from_bvh(?, ?)", (data, lenient)).fetchone()
        if m is None:
            error = "cannot read the file"
            if data is not None:
                (error,) = conn.execute("SELECT motion_bvh_error(?, ?)", (data, check)).fetchone()
            message = record_error(conn, path, error)
            print(f"[{i}/{len(paths)}] {path}: skipped: {message}", flush=True)
        else:
            stem = os.path.basename(path)[:-4]
            content, emotion = labels(stem)
            conn.execute(
                """INSERT OR REPLACE INTO motions(name, performer, content, emotion, fps, frames,
                                                  motion, source)
                   VALUES (?1, NULL, ?2, ?3, motion_fps(?4), motion_frames(?4), ?4, ?5)""",
                (stem, content, emotion, m, source))
            frames, joints = conn.execute("SELECT motion_frames(?1), motion_joints(?1)",
                                          (m,)).fetchone()
            conn.execute("DELETE FROM import_errors WHERE file = ?", (path,))
            imported += 1
            print(f"[{i}/{len(paths)}] {path}: {frames} frames, {joints} joints", flush=True)
        if time.monotonic() - committed >= 1:
            conn.commit()
            committed = time.monotonic()
    conn.commit()

    skipped = len(paths) - imported
    print(f"imported {imported} of {len(paths)} BVH files from {args.folder}; skipped {skipped}"
          + (" (recorded in import_errors)" if skipped else ""))
    conn.close()


if __name__ == "__main__":
    main()
