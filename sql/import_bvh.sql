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
--
-- A file that does not import (malformed, truncated, unreadable) does not stop the others: it
-- is skipped and recorded in import_errors with its line and a message such as
-- "motion_from_bvh: expected 120 frames, found 57 (data/walk_01.bvh, line 86)"; a file that
-- imports loses its old import_errors row. The script ends by printing how many files it
-- imported and skipped, and why each was skipped (sql/schema.sql creates import_errors; run it
-- again on a database made before the table existed: it only adds what is missing):
--
--   imported 173 of 174 BVH files from data; skipped 1 (recorded in import_errors)
--   skipped: motion_from_bvh: expected 120 frames, found 57 (data/walk_01.bvh, line 86)
--
-- Each file is parsed once (motion_from_bvh with {"on_error":"null"} gives NULL for a bad
-- file); only the bad ones are read again, by motion_bvh_error, for their message. Options
-- that are wrong for every file (a bad :unit) still stop the import with their error.
SAVEPOINT import_bvh;
DROP TABLE IF EXISTS temp.import_batch;
CREATE TEMP TABLE import_batch(path TEXT, stem TEXT, content TEXT, emotion TEXT, m BLOB,
                               error TEXT);

INSERT INTO temp.import_batch(path, stem, content, emotion, m)
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
)
SELECT path, stem, content, substr(rest2, 1, instr(rest2, '_') - 1),
       motion_from_bvh(readfile(path),
                       json_set(CASE WHEN :unit IS NULL THEN '{}'
                                     ELSE json_object('unit', :unit) END, '$.on_error', 'null'))
  FROM labels
 ORDER BY stem;

-- the message motion_from_bvh would have raised, for the files it could not import
UPDATE temp.import_batch
   SET error = coalesce(motion_bvh_error(readfile(path), CASE WHEN :unit IS NULL THEN NULL
                                                              ELSE json_object('unit', :unit) END),
                        'cannot read the file')
 WHERE m IS NULL;

DELETE FROM import_errors WHERE file IN (SELECT path FROM temp.import_batch);
INSERT INTO import_errors(file, line, message)
SELECT path,
       CASE WHEN error LIKE 'line %: %' THEN CAST(substr(error, 6) AS INTEGER) END,
       CASE WHEN error = 'cannot read the file'
            THEN 'readfile: cannot read the file (' || path || ')'
            WHEN error LIKE 'line %: %'
            THEN 'motion_from_bvh: ' || substr(error, instr(error, ': ') + 2) || ' (' || path ||
                 ', line ' || CAST(substr(error, 6) AS INTEGER) || ')'
            ELSE 'motion_from_bvh: ' || error || ' (' || path || ')' END
  FROM temp.import_batch
 WHERE m IS NULL;

INSERT OR REPLACE INTO motions(name, performer, content, emotion, fps, frames, motion, source)
SELECT stem, NULL, nullif(content, ''), nullif(emotion, ''), motion_fps(m), motion_frames(m), m,
       coalesce(:source, :dir)
  FROM temp.import_batch
 WHERE m IS NOT NULL
 ORDER BY stem;

SELECT printf('imported %d of %d BVH files from %s; skipped %d%s', count(m), count(*), :dir,
              count(*) - count(m),
              CASE WHEN count(m) < count(*) THEN ' (recorded in import_errors)' ELSE '' END)
  FROM temp.import_batch;
SELECT 'skipped: ' || message FROM import_errors
 WHERE file IN (SELECT path FROM temp.import_batch) ORDER BY file;
DROP TABLE temp.import_batch;
RELEASE import_bvh;
