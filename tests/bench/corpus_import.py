"""corpus_import.py — the corpora of ../shared/corpora imported into an SQLite database through
the extension: the one importer of the evaluation scripts of tests/bench (recognition_eval.py,
strength_eval.py, fda_eval.py, generation_eval.py, storage_eval.py). Python's standard library
and sqlite3 only.

Usage (from a script of tests/bench):
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import corpus_import as ci
    con = ci.connect(path)      # sqlite3 with the extension loaded (AFFECT_EXT, else build/affect)
    ci.import_corpora(con)      # both corpora; or ci.import_corpora(con, ["bandai-namco-1"])

import_corpora fills the table
    motions(id INTEGER PRIMARY KEY, source TEXT, name TEXT UNIQUE, content TEXT, style TEXT,
            frames INTEGER, motion BLOB)
with every *.bvh file of CORPORA/<source>/data, sorted by name: name is the file name without
".bvh", content and style its second and third "_"-separated fields (dataset-1_walk_angry_1),
motion = motion_from_bvh(text, '{"unit":"cm"}') and frames = motion_frames(motion). A source
whose row count already equals its number of files is left as it is, so a database that holds
the corpora is reused (several scripts can share one --db); otherwise its files are inserted
(INSERT OR REPLACE by name) and the rows committed.
"""
import os
import sqlite3

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CORPORA = os.path.join(ROOT, "..", "shared", "corpora")
EXT = os.environ.get("AFFECT_EXT", os.path.join(ROOT, "build", "affect"))

SOURCES = ("bandai-namco-1", "bandai-namco-2-dev")
# bandai-namco-1's four emotions and the ten contents recorded in every style
FOUR = ("angry", "happy", "sad", "normal")
TEN = ("walk", "run", "dash", "walk-back", "walk-left", "walk-right", "bow", "bye", "byebye",
       "guide")


def connect(db):
    """An sqlite3 connection to the file db with the extension EXT loaded."""
    con = sqlite3.connect(db)
    con.enable_load_extension(True)
    con.load_extension(EXT)
    return con


def import_corpora(con, sources=SOURCES):
    """Imports each corpus of sources into the table motions (see the module's comment)."""
    con.execute("CREATE TABLE IF NOT EXISTS motions(id INTEGER PRIMARY KEY, source TEXT, "
                "name TEXT UNIQUE, content TEXT, style TEXT, frames INTEGER, motion BLOB)")
    for source in sources:
        have = con.execute("SELECT count(*) FROM motions WHERE source = ?",
                           (source,)).fetchone()[0]
        data = os.path.join(CORPORA, source, "data")
        files = sorted(f for f in os.listdir(data) if f.endswith(".bvh"))
        if have == len(files):
            continue
        for f in files:
            _, content, style, _ = f[:-4].split("_")
            with open(os.path.join(data, f), encoding="utf-8") as fh:
                text = fh.read()
            con.execute("INSERT OR REPLACE INTO motions(source, name, content, style, motion) "
                        "VALUES (?, ?, ?, ?, motion_from_bvh(?, '{\"unit\":\"cm\"}'))",
                        (source, f[:-4], content, style, text))
        con.execute("UPDATE motions SET frames = motion_frames(motion) WHERE frames IS NULL")
        con.commit()
