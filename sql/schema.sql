-- schema.sql — the corpus schema every script and example uses.
--
--   sqlite3 demo.db < sql/schema.sql
--
-- One row per recording. `content` is the action performed (walk, bow, knock, …), `emotion`
-- the style or emotion label (angry, happy, sad, normal, …; the real corpus also has proud,
-- tired, old, …), `source` where it came from (a folder, or 'synth' for motion_synth).
CREATE TABLE IF NOT EXISTS motions(
    id        INTEGER PRIMARY KEY,
    name      TEXT NOT NULL UNIQUE,
    performer TEXT,
    content   TEXT,
    emotion   TEXT,
    fps       REAL,
    frames    INTEGER,
    motion    BLOB NOT NULL,
    source    TEXT
);
CREATE INDEX IF NOT EXISTS motions_emotion ON motions(emotion);
CREATE INDEX IF NOT EXISTS motions_content ON motions(content);

-- One row per file that sql/import_bvh.sql (or examples/import_folder.py) skipped: the file's
-- path, the line of the first problem (NULL when the file could not be read at all), the
-- message ("motion_from_bvh: expected 120 frames, found 57 (data/walk_01.bvh, line 86)") and
-- when. Importing the same file again replaces or, once it imports, deletes its row.
CREATE TABLE IF NOT EXISTS import_errors(
    file    TEXT PRIMARY KEY,
    line    INTEGER,
    message TEXT NOT NULL,
    at      TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%SZ', 'now'))
);
