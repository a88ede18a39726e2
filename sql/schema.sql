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
