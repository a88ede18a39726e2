-- import_bvh.sql — load every .bvh file of a folder into `motions` (sqlite3 shell only: it
-- uses the shell's fsdir() and readfile()). Labels come from file names of the form
-- dataset-1_{content}_{style}_{take}.bvh (the Bandai-Namco corpus); other names are imported
-- with NULL content and emotion. Re-running replaces rows of the same name.
--
--   sqlite3 demo.db -cmd '.load ./build/affect' \
--       -cmd ".parameter set :dir ../shared/corpora/bandai-namco-1/data" \
--       -cmd ".parameter set :unit cm" < sql/import_bvh.sql
--
-- :dir is the folder; :unit (optional, may be unset) is recorded in each motion BLOB; :source
-- (optional) labels the rows' source column (default: the folder).
WITH files AS (
    SELECT name AS path,
           replace(name, rtrim(name, replace(name, '/', '')), '') AS base
      FROM fsdir(:dir)
     WHERE name LIKE '%.bvh' AND (mode & 61440) = 32768  -- S_IFMT, S_IFREG: regular files
), stems AS (
    SELECT path, substr(base, 1, length(base) - 4) AS stem FROM files
), parts AS (
    SELECT path, stem,
           CASE WHEN stem LIKE 'dataset-%\_%\_%\_%' ESCAPE '\'
                THEN substr(stem, instr(stem, '_') + 1) END AS rest1
      FROM stems
), labels AS (
    SELECT path, stem,
           substr(rest1, 1, instr(rest1, '_') - 1) AS content,
           substr(rest1, instr(rest1, '_') + 1) AS rest2
      FROM parts
), parsed AS (
    SELECT path, stem, content,
           substr(rest2, 1, instr(rest2, '_') - 1) AS emotion,
           motion_from_bvh(CAST(readfile(path) AS TEXT),
                           CASE WHEN :unit IS NULL THEN NULL ELSE json_object('unit', :unit) END) AS m
      FROM labels
)
INSERT OR REPLACE INTO motions(name, performer, content, emotion, fps, frames, motion, source)
SELECT stem, NULL, nullif(content, ''), nullif(emotion, ''), motion_fps(m), motion_frames(m), m, coalesce(:source, :dir)
  FROM parsed
 ORDER BY stem;
