-- synth_corpus.sql — a synthetic affective corpus from motion_synth: every action × emotion
-- × performer seed 1..5 (4 × 4 × 5 = 80 motions), labelled like the real corpus.
--
--   sqlite3 demo.db -cmd '.load ./build/affect' < sql/synth_corpus.sql
WITH actions(action) AS (VALUES ('knock'), ('wave'), ('walk'), ('bow')),
     emotions(emotion) AS (VALUES ('neutral'), ('happy'), ('sad'), ('angry')),
     seeds(seed) AS (SELECT 1 UNION ALL SELECT seed + 1 FROM seeds WHERE seed < 5),
     made AS (
         SELECT action, emotion, seed, motion_synth(action, emotion, seed) AS m
           FROM actions, emotions, seeds
     )
INSERT OR REPLACE INTO motions(name, performer, content, emotion, fps, frames, motion, source)
SELECT printf('synth_%s_%s_%03d', action, emotion, seed), 'synth-' || seed, action, emotion,
       motion_fps(m), motion_frames(m), m, 'synth'
  FROM made
 ORDER BY action, emotion, seed;
