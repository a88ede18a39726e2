#!/usr/bin/env python3
"""quickstart.py — sqlite-affect from Python's standard sqlite3 module, loaded with the
package in python/ (sqlite_affect.load).

    python3 examples/quickstart.py [path/to/build/affect] [path/to/file.bvh]

Loads the extension, makes a few synthetic affective movements, imports a BVH file when one is
given, and shows the motion functions: information, JSON interchange, roles, points and an SVG
preview written next to this script's working directory.
"""
import json
import os
import sqlite3
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "python"))  # the package of this checkout
import sqlite_affect  # noqa: E402  (or: pip install ./python)

MODULE = sys.argv[1] if len(sys.argv) > 1 else None  # None: sqlite_affect.load finds it
BVH = sys.argv[2] if len(sys.argv) > 2 else None


def connect():
    conn = sqlite3.connect(":memory:")
    try:
        sqlite_affect.load(conn, MODULE)
    except sqlite_affect.LoadError as e:  # says what to use instead, or what was not found
        sys.exit(f"{e}\nBuild it first: ./run.sh demo (or cmake -S . -B build && cmake --build build)")
    return conn


def main():
    conn = connect()
    print("affect", conn.execute("SELECT affect_version()").fetchone()[0])
    conn.executescript(open(os.path.join(HERE, "..", "sql", "schema.sql")).read())

    # three performers knocking with four emotions
    conn.execute("""
        WITH made AS (
            SELECT e.value AS emotion, s.value AS seed, motion_synth('knock', e.value, s.value) AS m
              FROM json_each('["neutral","happy","sad","angry"]') AS e, json_each('[1,2,3]') AS s)
        INSERT INTO motions(name, performer, content, emotion, fps, frames, motion, source)
        SELECT printf('knock_%s_%d', emotion, seed), 'synth-' || seed, 'knock', emotion,
               motion_fps(m), motion_frames(m), m, 'synth'
          FROM made""")
    if BVH:
        text = open(BVH, encoding="utf-8").read()
        conn.execute("""INSERT INTO motions(name, motion, fps, frames, source)
                        SELECT ?, m, motion_fps(m), motion_frames(m), 'file'
                          FROM (SELECT motion_from_bvh(?) AS m)""", (os.path.basename(BVH), text))

    print("\nduration by emotion (seconds):")
    for emotion, seconds in conn.execute("""
            SELECT emotion, round(avg(motion_duration(motion)), 2) FROM motions
             WHERE source = 'synth' GROUP BY emotion ORDER BY 2"""):
        print(f"  {emotion:8s} {seconds}")

    # JSON is the interchange form: a motion becomes plain Python lists
    (doc,) = conn.execute("SELECT motion_to_json(motion) FROM motions WHERE name = 'knock_sad_1'").fetchone()
    motion = json.loads(doc)
    print(f"\nknock_sad_1: {len(motion['frames'])} frames x {len(motion['joints'])} joints at {motion['fps']} fps")
    hand = motion["joints"].index("Hand_R")
    peak = max(frame[hand][1] for frame in motion["frames"])
    print(f"  highest right hand: {peak:.3f} {motion.get('unit', '')}")
    # … and back: a motion edited in Python is stored again
    motion["frames"] = motion["frames"][::2]
    motion["fps"] = motion["fps"] / 2
    (frames,) = conn.execute("SELECT motion_frames(motion_from_json(?))", (json.dumps(motion),)).fetchone()
    print(f"  every other frame, back in SQL: {frames} frames")

    (roles,) = conn.execute("SELECT motion_roles(motion) FROM motions WHERE name = 'knock_angry_1'").fetchone()
    roles = json.loads(roles)
    print("\nroles:", ", ".join(f"{k}={roles[k]}" for k in ("pelvis", "head", "left_hand", "right_hand")))

    rows = conn.execute("""SELECT frame, round(x, 3), round(y, 3), round(z, 3)
                             FROM motion_points((SELECT motion FROM motions WHERE name = 'knock_angry_1'))
                            WHERE name = 'Hand_R' AND frame % 20 = 0""").fetchall()
    print("\nright hand of knock_angry_1 every 20 frames (frame, x, y, z):")
    for r in rows:
        print("  ", r)

    try:
        conn.execute("SELECT motion_info('not a motion')")
    except sqlite3.OperationalError as e:
        print("\nerrors are clear:", e)

    (svg,) = conn.execute("""SELECT motion_svg(motion, '{"frames": 6, "title": "knock, angry"}')
                               FROM motions WHERE name = 'knock_angry_1'""").fetchone()
    with open("quickstart.svg", "w", encoding="utf-8") as f:
        f.write(svg)
    print(f"\nwrote quickstart.svg ({len(svg)} bytes): open it in a browser")


if __name__ == "__main__":
    main()
