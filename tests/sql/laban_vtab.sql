-- laban_vtab.sql — SQL-level specification of the laban virtual table (ext/vt_laban.c):
-- cached descriptors, k-nearest and radius queries checked against a brute force written in
-- SQL, every error message, the commands, the stale check, the triggers of
-- sql/laban_triggers.sql, shadow tables, rename and drop. Run by tests/sql/test_sql.c (see its
-- header for the annotation format); each SELECT without an annotation must give 1 in its
-- second column.

-- ---- a content table: 4 actions × 4 emotions × 3 performers ----
CREATE TABLE motions(
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

WITH actions(action) AS (VALUES ('knock'), ('wave'), ('walk'), ('bow')),
     emotions(emotion) AS (VALUES ('neutral'), ('happy'), ('sad'), ('angry')),
     seeds(seed) AS (VALUES (1), (2), (3))
INSERT INTO motions(name, performer, content, emotion, motion, source)
SELECT printf('synth_%s_%s_%03d', action, emotion, seed), 'synth-' || seed, action, emotion,
       motion_synth(action, emotion, seed), 'synth'
  FROM actions, emotions, seeds
 ORDER BY action, emotion, seed;

SELECT 'rows 1-3 are bow/angry', group_concat(id) = '1,2,3' FROM motions
 WHERE content = 'bow' AND emotion = 'angry';

SELECT 'the module is registered', count(*) = 1 FROM pragma_module_list WHERE name = 'laban';

CREATE VIRTUAL TABLE motion_laban USING laban(content=motions, motion=motion, label=emotion);

-- ---- the declared schema ----
SELECT group_concat(name, ' ') FROM pragma_table_xinfo('motion_laban') WHERE hidden <> 0;
-- expect: distance query k radius components motion_laban

SELECT 'visible columns: label, then laban_names() in order',
       (SELECT group_concat(name) FROM pragma_table_info('motion_laban')) =
       'label,' || (SELECT group_concat(value) FROM json_each(laban_names()));

-- ---- cached rows ----
SELECT count(*) FROM motion_laban;
-- expect: 48

SELECT group_concat(label || ':' || n, ' ') FROM
  (SELECT label, count(*) AS n FROM motion_laban GROUP BY label ORDER BY label);
-- expect: angry:12 happy:12 neutral:12 sad:12

SELECT 'rowids and labels are the content rows''s', count(*) = 48 FROM motion_laban l
  JOIN motions m ON m.id = l.rowid WHERE l.label = m.emotion;

SELECT 'a full scan has no distance', count(*) = 48 FROM motion_laban WHERE distance IS NULL;

-- the scalar functions are the reference
CREATE TEMP TABLE ref AS SELECT id, laban(motion) AS j, laban_vector(motion) AS v FROM motions;

CREATE TEMP TABLE refc AS SELECT r.id, n.key AS i, json_extract(r.j, '$.' || n.value) AS x
  FROM ref AS r, json_each(laban_names()) AS n;

SELECT 'the cached vectors are laban_vector() byte for byte', count(*) = 48
  FROM motion_laban_data d JOIN ref r ON r.id = d.id WHERE d.vector = r.v;

SELECT 'cached WeightAll and TimeAll are laban() rounded to float32', count(*) = 48
  FROM motion_laban l JOIN ref r ON r.id = l.rowid
 WHERE abs(l.WeightAll - json_extract(r.j, '$.WeightAll'))
       <= 1e-6 * json_extract(r.j, '$.WeightAll')
   AND abs(l.TimeAll - json_extract(r.j, '$.TimeAll')) <= 1e-6 * json_extract(r.j, '$.TimeAll');

SELECT 'msize and mhash describe the motion BLOB', count(*) = 48, count(DISTINCT d.mhash)
  FROM motion_laban_data d JOIN motions m ON m.id = d.id WHERE d.msize = length(m.motion);

-- ---- the _info shadow table ----
SELECT group_concat(key, ' ') FROM (SELECT key FROM motion_laban_info ORDER BY key);
-- expect: content format generation label mean motion options rows sd stats_generation

SELECT group_concat(value, ' ') FROM (SELECT value FROM motion_laban_info
  WHERE key IN ('format', 'content', 'motion', 'label', 'rows') ORDER BY key);
-- expect: motions 1 emotion motion 48

SELECT value FROM motion_laban_info WHERE key = 'options';
-- expect: {"cutoff_hz":6,"hull":"convex","speed_floor":0.05,"max_ratio":100,"up":"y","per_second":false}

-- the cached columns unpivoted (component i = 0..26, NULL where missing), and standardized with
-- the mean and sd of _info
CREATE TEMP TABLE lv AS
WITH n(i) AS (SELECT 0 UNION ALL SELECT i + 1 FROM n WHERE i < 26)
SELECT l.rowid AS id, l.label AS label, n.i AS i,
       CASE n.i WHEN 0 THEN WeightAll WHEN 1 THEN WeightTorso WHEN 2 THEN WeightHead
           WHEN 3 THEN WeightLHand WHEN 4 THEN WeightRHand WHEN 5 THEN WeightLFoot
           WHEN 6 THEN WeightRFoot WHEN 7 THEN TimeAll WHEN 8 THEN TimeTorso WHEN 9 THEN TimeHead
           WHEN 10 THEN TimeLHand WHEN 11 THEN TimeRHand WHEN 12 THEN TimeLFoot
           WHEN 13 THEN TimeRFoot WHEN 14 THEN FlowAll WHEN 15 THEN FlowTorso WHEN 16 THEN FlowHead
           WHEN 17 THEN FlowLHand WHEN 18 THEN FlowRHand WHEN 19 THEN FlowLFoot
           WHEN 20 THEN FlowRFoot WHEN 21 THEN ShapeVertical WHEN 22 THEN ShapeSagittal
           WHEN 23 THEN ShapeHorizontal WHEN 24 THEN ShapeFlow WHEN 25 THEN ShapeDirLHand
           WHEN 26 THEN ShapeDirRHand END AS x
  FROM motion_laban AS l, n;

SELECT 'every component agrees with laban()', count(*) = 48 * 27
  FROM lv JOIN refc USING (id, i)
 WHERE (lv.x IS NULL AND refc.x IS NULL) OR abs(lv.x - refc.x) <= 1e-6 * abs(refc.x);

CREATE TEMP TABLE zs AS
SELECT lv.id, lv.label, lv.i, lv.x,
       (lv.x - json_extract(mean.value, '$[' || lv.i || ']')) /
       json_extract(sd.value, '$[' || lv.i || ']') AS z
  FROM lv, motion_laban_info AS mean, motion_laban_info AS sd
 WHERE mean.key = 'mean' AND sd.key = 'sd';

SELECT 'mean is the average, sd the sample standard deviation (n - 1)', count(*) = 27
  FROM (SELECT i, avg(x) AS mean, count(x) AS n FROM lv GROUP BY i) AS a
  JOIN (SELECT lv.i, sqrt(sum((x - a2.mean) * (x - a2.mean)) / (count(x) - 1)) AS sd
          FROM lv JOIN (SELECT i, avg(x) AS mean FROM lv GROUP BY i) AS a2 USING (i)
         GROUP BY lv.i) AS b USING (i),
       motion_laban_info AS m, motion_laban_info AS s
 WHERE m.key = 'mean' AND s.key = 'sd'
   AND abs(a.mean - json_extract(m.value, '$[' || i || ']')) <= 1e-12 * abs(a.mean)
   AND abs(b.sd - json_extract(s.value, '$[' || i || ']')) <= 1e-12 * b.sd;

-- brute-force distances between every pair: all 27 components, and TimeAll + FlowAll (7, 14)
CREATE TEMP TABLE dist AS
SELECT a.id AS q, b.id AS id, b.label AS label,
       sqrt(sum((a.z - b.z) * (a.z - b.z))) AS d,
       sqrt(sum(CASE WHEN a.i IN (7, 14) THEN (a.z - b.z) * (a.z - b.z) END)) AS d_tf
  FROM zs AS a JOIN zs AS b ON a.i = b.i
 WHERE a.z IS NOT NULL AND b.z IS NOT NULL
 GROUP BY a.id, b.id;

-- ---- k nearest ----
SELECT 'k = 5 nearest angry to row 2 (query by rowid: itself excluded)',
       (SELECT group_concat(rowid, ' ') FROM motion_laban
         WHERE query = 2 AND label = 'angry' AND k = 5) =
       (SELECT group_concat(id, ' ') FROM (SELECT id FROM dist
         WHERE q = 2 AND id <> 2 AND label = 'angry' ORDER BY d, id LIMIT 5));

SELECT 'their distances are the brute force''s', count(*) = 5 AND max(abs(l.distance - t.d)) < 1e-9
  FROM motion_laban AS l JOIN dist AS t ON t.q = 2 AND t.id = l.rowid
 WHERE l.query = 2 AND l.label = 'angry' AND l.k = 5;

SELECT 'k = 7 over every label', (SELECT group_concat(rowid, ' ') FROM motion_laban
         WHERE query = 30 AND k = 7) =
       (SELECT group_concat(id, ' ') FROM (SELECT id FROM dist
         WHERE q = 30 AND id <> 30 ORDER BY d, id LIMIT 7));

SELECT 'rows come by distance ascending', count(*) = 47,
       sum(distance >= prev) = 46 FROM (SELECT distance, lag(distance) OVER () AS prev
  FROM motion_laban WHERE query = 30 AND k = 100);

SELECT 'k larger than the candidates gives them all', count(*) = 11
  FROM motion_laban WHERE query = 2 AND label = 'angry' AND k = 1000;

SELECT 'k with components', (SELECT group_concat(rowid, ' ') FROM motion_laban
         WHERE query = 2 AND k = 6 AND components = '["TimeAll","FlowAll"]') =
       (SELECT group_concat(id, ' ') FROM (SELECT id FROM dist
         WHERE q = 2 AND id <> 2 ORDER BY d_tf, id LIMIT 6));

SELECT 'component distances are the brute force''s', count(*) = 6
       AND max(abs(l.distance - t.d_tf)) < 1e-9
  FROM motion_laban AS l JOIN dist AS t ON t.q = 2 AND t.id = l.rowid
 WHERE l.query = 2 AND l.k = 6 AND l.components = '["TimeAll","FlowAll"]';

SELECT 'the order of the components does not matter',
       (SELECT group_concat(rowid || ':' || distance, ' ') FROM motion_laban
         WHERE query = 2 AND k = 6 AND components = '["FlowAll","TimeAll"]') =
       (SELECT group_concat(rowid || ':' || distance, ' ') FROM motion_laban
         WHERE query = 2 AND k = 6 AND components = '["TimeAll","FlowAll"]');

SELECT 'components = NULL means all of them',
       (SELECT group_concat(rowid || ':' || distance) FROM motion_laban
         WHERE query = 2 AND k = 4 AND components = NULL) =
       (SELECT group_concat(rowid || ':' || distance) FROM motion_laban WHERE query = 2 AND k = 4);

SELECT 'a motion BLOB query finds itself first, at distance 0, then the same rows',
       (SELECT group_concat(rowid || ':' || distance, ' ') FROM motion_laban
         WHERE query = (SELECT motion FROM motions WHERE id = 2) AND label = 'angry' AND k = 6) =
       '2:0.0 ' || (SELECT group_concat(rowid || ':' || distance, ' ') FROM motion_laban
         WHERE query = 2 AND label = 'angry' AND k = 5);

SELECT 'ORDER BY distance DESC is honoured',
       (SELECT group_concat(rowid, ' ') FROM (SELECT rowid FROM motion_laban
         WHERE query = 2 AND k = 5 ORDER BY distance DESC)) =
       (SELECT group_concat(id, ' ') FROM (SELECT id FROM (SELECT id, d FROM dist
         WHERE q = 2 AND id <> 2 ORDER BY d, id LIMIT 5) ORDER BY d DESC, id DESC));

SELECT 'LIMIT cuts the k nearest',
       (SELECT group_concat(rowid) FROM (SELECT rowid FROM motion_laban
         WHERE query = 2 AND k = 10 ORDER BY distance LIMIT 3)) =
       (SELECT group_concat(rowid) FROM (SELECT rowid FROM motion_laban WHERE query = 2 AND k = 3));

SELECT 'the hidden columns give the constraints back', group_concat(DISTINCT k || ' ' || components)
       = '3 ["TimeAll"]'
  FROM motion_laban WHERE query = 2 AND k = 3 AND components = '["TimeAll"]';

SELECT 'a rowid constraint restricts the candidates', group_concat(rowid) = '17'
  FROM motion_laban WHERE query = 2 AND k = 5 AND rowid = 17;

SELECT 'query = NULL matches nothing', count(*) = 0 FROM motion_laban WHERE query = NULL AND k = 3;

SELECT 'query in a join (one search per outer row)', count(*) = 6,
       count(DISTINCT q.id) = 3 FROM motions AS q, motion_laban AS l
 WHERE q.id IN (1, 20, 40) AND l.query = q.id AND l.k = 2;

-- ---- radius: the thesis's ε-neighbourhood ----
-- (over all 27 components distances concentrate: the sad motions lie 4.2 to 5.0 from row 2)
SELECT 'radius 0.9 around row 2 among sad motions',
       (SELECT group_concat(rowid, ' ') FROM motion_laban
         WHERE query = 2 AND label = 'sad' AND radius = 0.9) =
       (SELECT group_concat(id, ' ') FROM (SELECT id FROM dist,
          (SELECT max(d) AS dmax FROM dist WHERE q = 2 AND id <> 2 AND label = 'sad')
         WHERE q = 2 AND id <> 2 AND label = 'sad' AND d <= 0.9 * dmax ORDER BY d, id));

SELECT 'radius 0.9 holds several rows here, not all', count(*) BETWEEN 2 AND 11
  FROM motion_laban WHERE query = 2 AND label = 'sad' AND radius = 0.9;

SELECT 'radius 1 holds every candidate', count(*) = 12
  FROM motion_laban WHERE query = 2 AND label = 'sad' AND radius = 1;

SELECT 'an empty ball still gives the nearest one',
       (SELECT group_concat(rowid) FROM motion_laban
         WHERE query = 2 AND label = 'sad' AND radius = 0.0001) =
       (SELECT group_concat(rowid) FROM motion_laban WHERE query = 2 AND label = 'sad' AND k = 1);

SELECT 'radius with components',
       (SELECT group_concat(rowid, ' ') FROM motion_laban
         WHERE query = 5 AND radius = 0.2 AND components = '["TimeAll","FlowAll"]') =
       (SELECT group_concat(id, ' ') FROM (SELECT id FROM dist,
          (SELECT max(d_tf) AS dmax FROM dist WHERE q = 5 AND id <> 5)
         WHERE q = 5 AND id <> 5 AND d_tf <= 0.2 * dmax ORDER BY d_tf, id));

-- ---- full scans ----
SELECT 'label = filters a scan', count(*) = 12, min(label) = 'sad' AND max(label) = 'sad'
  FROM motion_laban WHERE label = 'sad';

SELECT l.rowid || ' ' || m.content || '-' || l.label FROM motion_laban AS l
  JOIN motions AS m ON m.id = l.rowid WHERE l.rowid = 7;
-- expect: 7 bow-neutral

SELECT 'an absent rowid gives nothing', count(*) = 0 FROM motion_laban WHERE rowid = 999;

SELECT 'rowid constraints have INTEGER affinity',
       (SELECT group_concat(rowid) FROM motion_laban WHERE rowid = '7') = '7' AND
       (SELECT group_concat(rowid) FROM motion_laban WHERE rowid = 8.0) = '8';

SELECT 'a scan comes in rowid order', group_concat(rowid) = '1,2,3,4,5'
  FROM (SELECT rowid FROM motion_laban ORDER BY rowid LIMIT 5);

SELECT 'the hidden columns are NULL in a scan', count(*) = 48 FROM motion_laban
 WHERE query IS NULL AND k IS NULL AND radius IS NULL AND components IS NULL
   AND motion_laban IS NULL;

-- ---- planning errors ----
SELECT rowid FROM motion_laban WHERE query = 2;
-- error: laban: a k or radius constraint is required for a query

SELECT rowid FROM motion_laban WHERE query = 2 AND k = 3 AND radius = 0.1;
-- error: laban: use either k or radius, not both

SELECT rowid FROM motion_laban WHERE k = 3;
-- error: laban: k, radius and components need a query constraint

SELECT rowid FROM motion_laban WHERE radius = 0.5 AND label = 'sad';
-- error: laban: k, radius and components need a query constraint

SELECT rowid FROM motion_laban WHERE components = '["TimeAll"]';
-- error: laban: k, radius and components need a query constraint

-- ---- query errors ----
SELECT rowid FROM motion_laban WHERE query = 'walk' AND k = 3;
-- error: laban: query must be a motion BLOB or a rowid of the content table, got text

SELECT rowid FROM motion_laban WHERE query = 2.5 AND k = 3;
-- error: laban: query must be a motion BLOB or a rowid of the content table, got real

SELECT rowid FROM motion_laban WHERE query = 999 AND k = 3;
-- error: laban: no row 999 in the index

SELECT rowid FROM motion_laban WHERE query = x'41464d4f' AND k = 3;
-- error: laban: query is not a valid motion: truncated: 4 bytes is shorter than the 32-byte header

SELECT rowid FROM motion_laban WHERE query = 2 AND k = 0;
-- error: laban: k must be a positive integer, got 0

SELECT rowid FROM motion_laban WHERE query = 2 AND k = 2.5;
-- error: laban: k must be a positive integer, got 2.5

SELECT rowid FROM motion_laban WHERE query = 2 AND k = 'five';
-- error: laban: k must be a positive integer, got text

SELECT rowid FROM motion_laban WHERE query = 2 AND k = NULL;
-- error: laban: k must be a positive integer, got null

SELECT 'k may be an integral real', count(*) = 2 FROM motion_laban WHERE query = 2 AND k = 2.0;

SELECT rowid FROM motion_laban WHERE query = 2 AND radius = 2;
-- error: laban: radius must be in (0, 1], got 2

SELECT rowid FROM motion_laban WHERE query = 2 AND radius = 0;
-- error: laban: radius must be in (0, 1], got 0

SELECT rowid FROM motion_laban WHERE query = 2 AND radius = '0.1';
-- error: laban: radius must be in (0, 1], got text

SELECT rowid FROM motion_laban WHERE query = 2 AND k = 3 AND components = '["TimeAll","Foo"]';
-- error: laban: unknown component "Foo" (see laban_names())

SELECT rowid FROM motion_laban WHERE query = 2 AND k = 3 AND components = '[]';
-- error: laban: components must name at least one component

SELECT rowid FROM motion_laban WHERE query = 2 AND k = 3 AND components = '["TimeAll","TimeAll"]';
-- error: laban: component "TimeAll" is listed twice

SELECT rowid FROM motion_laban WHERE query = 2 AND k = 3 AND components = 'TimeAll';
-- error: laban: components must be a JSON array of component names: at byte 0: invalid literal

SELECT rowid FROM motion_laban WHERE query = 2 AND k = 3 AND components = '{"TimeAll":1}';
-- error: laban: components must be a JSON array of component names, got object

SELECT rowid FROM motion_laban WHERE query = 2 AND k = 3 AND components = '["TimeAll",7]';
-- error: laban: components must be a JSON array of component names, got number in it

SELECT rowid FROM motion_laban WHERE query = 2 AND k = 3 AND components = x'00';
-- error: laban: components must be a JSON array of component names, got blob

-- ---- writes are commands ----
INSERT INTO motion_laban(label) VALUES('sad');
-- error: laban: the index is read-only: change the content table and run 'rebuild', or install the triggers of sql/laban_triggers.sql

UPDATE motion_laban SET label = 'sad' WHERE rowid = 1;
-- error: laban: the index is read-only: change the content table and run 'rebuild', or install the triggers of sql/laban_triggers.sql

DELETE FROM motion_laban WHERE rowid = 1;
-- error: laban: the index is read-only: change the content table and run 'rebuild', or install the triggers of sql/laban_triggers.sql

INSERT INTO motion_laban(motion_laban) VALUES('rebuidl');
-- error: laban: unknown command "rebuidl" (expected rebuild, refresh, delete, check)

INSERT INTO motion_laban(motion_laban) VALUES('refresh');
-- error: laban: 'refresh' needs a rowid, as in INSERT INTO motion_laban(motion_laban, rowid) VALUES('refresh', 12)

INSERT INTO motion_laban(motion_laban) VALUES('delete');
-- error: laban: 'delete' needs a rowid, as in INSERT INTO motion_laban(motion_laban, rowid) VALUES('delete', 12)

INSERT INTO motion_laban(motion_laban) VALUES('check');

-- ---- stale rows: 'check', 'refresh', 'delete', 'rebuild' ----
UPDATE motions SET motion = motion_synth('walk', 'angry', 7) WHERE id = 4;
DELETE FROM motions WHERE id = 10;
INSERT INTO motions(id, name, content, emotion, motion)
VALUES (49, 'extra', 'wave', 'sad', motion_synth('wave', 'sad', 9));

INSERT INTO motion_laban(motion_laban) VALUES('check');
-- error: laban: 3 rows are stale (first: rowid 4); run INSERT INTO motion_laban(motion_laban) VALUES('rebuild')

SELECT 'the cache still holds the old rows', count(*) = 48, sum(rowid = 10) = 1 FROM motion_laban;

INSERT INTO motion_laban(motion_laban, rowid) VALUES('refresh', 4);

SELECT 'refresh recomputed row 4', d.vector = laban_vector(m.motion)
  FROM motion_laban_data AS d JOIN motions AS m ON m.id = d.id WHERE d.id = 4;

INSERT INTO motion_laban(motion_laban) VALUES('check');
-- error: laban: 2 rows are stale (first: rowid 10); run INSERT INTO motion_laban(motion_laban) VALUES('rebuild')

INSERT INTO motion_laban(motion_laban, rowid) VALUES('refresh', 10);

INSERT INTO motion_laban(motion_laban) VALUES('check');
-- error: laban: 1 row is stale (first: rowid 49); run INSERT INTO motion_laban(motion_laban) VALUES('rebuild')

INSERT INTO motion_laban(motion_laban, rowid) VALUES('refresh', 49);
INSERT INTO motion_laban(motion_laban) VALUES('check');

SELECT 'row 10 left the index, row 49 joined it', count(*) = 48, sum(rowid = 10) = 0,
       sum(rowid = 49 AND label = 'sad') = 1 FROM motion_laban;

SELECT 'the statistics follow the rows', value = 48 FROM motion_laban_info WHERE key = 'rows';

SELECT 'the mean follows the rows', abs(json_extract(value, '$[0]') -
       (SELECT avg(WeightAll) FROM motion_laban)) < 1e-9 * json_extract(value, '$[0]')
  FROM motion_laban_info WHERE key = 'mean';

INSERT INTO motion_laban(motion_laban, rowid) VALUES('delete', 12);

INSERT INTO motion_laban(motion_laban) VALUES('check');
-- error: laban: 1 row is stale (first: rowid 12); run INSERT INTO motion_laban(motion_laban) VALUES('rebuild')

SELECT 'delete removed row 12', count(*) = 47, sum(rowid = 12) = 0 FROM motion_laban;

SELECT rowid FROM motion_laban WHERE query = 12 AND k = 1;
-- error: laban: no row 12 in the index

UPDATE motions SET emotion = 'sad' WHERE id = 5;

INSERT INTO motion_laban(motion_laban) VALUES('check');
-- error: laban: 2 rows are stale (first: rowid 5); run INSERT INTO motion_laban(motion_laban) VALUES('rebuild')

INSERT INTO motion_laban(motion_laban) VALUES('rebuild');
INSERT INTO motion_laban(motion_laban) VALUES('check');

SELECT 'rebuild brought everything back', count(*) = 48, sum(rowid = 5 AND label = 'sad') = 1,
       sum(rowid = 12) = 1 FROM motion_laban;

INSERT INTO motion_laban(motion_laban, rowid) VALUES('refresh', 12345);
INSERT INTO motion_laban(motion_laban, rowid) VALUES('delete', 12345);
INSERT INTO motion_laban(motion_laban) VALUES('check');

SELECT 'refresh and delete of an absent row change nothing', count(*) = 48 FROM motion_laban;

-- ---- the triggers of sql/laban_triggers.sql (copied verbatim) ----
CREATE TRIGGER IF NOT EXISTS motions_laban_insert AFTER INSERT ON motions BEGIN
    INSERT INTO motion_laban(motion_laban, rowid) VALUES('refresh', new.rowid);
END;

CREATE TRIGGER IF NOT EXISTS motions_laban_update AFTER UPDATE ON motions BEGIN
    INSERT INTO motion_laban(motion_laban, rowid)
    SELECT 'delete', old.rowid WHERE old.rowid IS NOT new.rowid;
    INSERT INTO motion_laban(motion_laban, rowid) VALUES('refresh', new.rowid);
END;

CREATE TRIGGER IF NOT EXISTS motions_laban_delete AFTER DELETE ON motions BEGIN
    INSERT INTO motion_laban(motion_laban, rowid) VALUES('delete', old.rowid);
END;

INSERT INTO motions(id, name, content, emotion, motion)
VALUES (60, 'new', 'knock', 'angry', motion_synth('knock', 'angry', 60));

SELECT 'an insert is indexed', d.vector = laban_vector(m.motion) AND d.label = 'angry'
  FROM motion_laban_data AS d JOIN motions AS m ON m.id = d.id WHERE d.id = 60;

UPDATE motions SET motion = motion_synth('bow', 'sad', 61) WHERE id = 60;

SELECT 'a new motion is recomputed', d.vector = laban_vector(m.motion)
  FROM motion_laban_data AS d JOIN motions AS m ON m.id = d.id WHERE d.id = 60;

UPDATE motions SET emotion = 'sad', name = 'renamed' WHERE id = 60;

SELECT label FROM motion_laban WHERE rowid = 60;
-- expect: sad

UPDATE motions SET id = 70 WHERE id = 60;

SELECT 'a new rowid moves the row', group_concat(rowid) = '70' FROM motion_laban
 WHERE rowid IN (60, 70);

DELETE FROM motions WHERE id IN (70, 1);

SELECT 'a delete leaves the index', count(*) = 47, sum(rowid IN (1, 70)) = 0 FROM motion_laban;

-- one statement, one transaction: a temporary trigger looks at the index while it runs
-- (explicit BEGIN … COMMIT are left out: the harness injects faults into COMMIT itself)
CREATE TEMP TABLE seen(what, n);

CREATE TEMP TRIGGER watch AFTER INSERT ON main.motions WHEN new.id = 81 BEGIN
    INSERT INTO seen SELECT 'row 80', count(*) FROM motion_laban WHERE rowid = 80;
    INSERT INTO seen SELECT 'rows in _info', value FROM motion_laban_info WHERE key = 'rows';
END;

INSERT INTO motions(id, name, content, emotion, motion)
VALUES (80, 'a', 'walk', 'happy', motion_synth('walk', 'happy', 80)),
       (81, 'b', 'walk', 'sad', motion_synth('walk', 'sad', 81));

DROP TRIGGER watch;

SELECT 'queries inside a transaction see its changes; _info catches up at commit',
       group_concat(what || ' ' || n, ', ') = 'row 80 1, rows in _info 47' FROM seen;

INSERT INTO motion_laban(motion_laban) VALUES('check');

SELECT 'the statistics were recomputed at commit', value = 49 FROM motion_laban_info
 WHERE key = 'rows';

SELECT 'every write bumped the generation', value > 10 FROM motion_laban_info
 WHERE key = 'generation';

-- ---- determinism and options: a second index over the same rows ----
CREATE VIRTUAL TABLE again USING laban(content = 'motions', label = "emotion");

SELECT 'same data, byte-identical vectors and statistics', count(*) = 49
  FROM again_data AS a JOIN motion_laban_data AS b USING (id)
 WHERE a.vector = b.vector AND a.mhash = b.mhash AND a.label IS b.label;

SELECT 'same mean and sd text', count(*) = 2 FROM again_info AS a JOIN motion_laban_info AS b
 USING (key) WHERE key IN ('mean', 'sd') AND a.value = b.value;

SELECT 'same answers', (SELECT group_concat(rowid || ':' || distance) FROM again
         WHERE query = 2 AND radius = 0.4) =
       (SELECT group_concat(rowid || ':' || distance) FROM motion_laban
         WHERE query = 2 AND radius = 0.4);

DROP TABLE again;

CREATE VIRTUAL TABLE boxed USING laban(content=motions, label=emotion,
    options='{"hull": "box", "cutoff_hz": 4, "up": "y"}');

SELECT value FROM boxed_info WHERE key = 'options';
-- expect: {"cutoff_hz":4,"hull":"box","speed_floor":0.05,"max_ratio":100,"up":"y","per_second":false}

CREATE TEMP TABLE boxed_ref AS SELECT m.id, laban_vector(m.motion, o.value) AS v
  FROM motions AS m, boxed_info AS o WHERE o.key = 'options';

SELECT 'the options reach the descriptors (laban_vector with the same options)', count(*) = 49
  FROM boxed_data AS d JOIN boxed_ref AS r USING (id) WHERE d.vector = r.v;

SELECT 'and they change them', count(*) = 49 FROM boxed_data AS a JOIN motion_laban_data AS b
 USING (id) WHERE a.vector <> b.vector;

DROP TABLE boxed;

-- ---- constructor errors ----
CREATE VIRTUAL TABLE bad USING laban(content=motionz);
-- error: laban: no such table: motionz

CREATE VIRTUAL TABLE bad USING laban(content=motions, motion=mot);
-- error: laban: no column "mot" in table motions

CREATE VIRTUAL TABLE bad USING laban(content=motions);
-- error: laban: no column "label" in table motions

CREATE VIRTUAL TABLE bad USING laban(label=emotion);
-- error: laban: the content argument is required, as in CREATE VIRTUAL TABLE bad USING laban(content=motions, motion=motion, label=emotion)

CREATE VIRTUAL TABLE bad USING laban(content=motions, label=emotion, content=others);
-- error: laban: duplicate argument "content"

CREATE VIRTUAL TABLE bad USING laban(contnet=motions);
-- error: laban: unknown argument "contnet" (expected content, motion, label, options)

CREATE VIRTUAL TABLE bad USING laban(motions);
-- error: laban: expected key=value, got "motions"

CREATE VIRTUAL TABLE bad USING laban(content=motions, label=);
-- error: laban: argument "label" needs a value

CREATE VIRTUAL TABLE bad USING laban(content='motions' x, label=emotion);
-- error: laban: argument "content": unexpected text after the closing quote

CREATE VIRTUAL TABLE bad USING laban(content='mo''tions');
-- error: laban: no such table: mo'tions

CREATE VIRTUAL TABLE bad USING laban(content=motions, label=emotion, options='{"cutoff_hz": -1}');
-- error: laban: option "cutoff_hz" must be a positive number, got -1

CREATE VIRTUAL TABLE bad USING laban(content=motions, label=emotion, options='{"cutoff_hz": "6"}');
-- error: laban: option "cutoff_hz" must be a number, got string

CREATE VIRTUAL TABLE bad USING laban(content=motions, label=emotion, options='{"speed_floor": 1}');
-- error: laban: option "speed_floor" must be in [0, 1), got 1

CREATE VIRTUAL TABLE bad USING laban(content=motions, label=emotion, options='{"max_ratio": 0.5}');
-- error: laban: option "max_ratio" must be at least 1, got 0.5

CREATE VIRTUAL TABLE bad USING laban(content=motions, label=emotion, options='{"hull": "round"}');
-- error: laban: option "hull" must be "convex" or "box", got "round"

CREATE VIRTUAL TABLE bad USING laban(content=motions, label=emotion, options='{"up": 1}');
-- error: laban: option "up" must be "x", "y" or "z", got number

CREATE VIRTUAL TABLE bad USING laban(content=motions, label=emotion, options='{"per_second": 1}');
-- error: laban: option "per_second" must be true or false, got number

CREATE VIRTUAL TABLE bad USING laban(content=motions, label=emotion, options='{"roles": {}}');
-- error: laban: unknown option "roles" (expected cutoff_hz, hull, speed_floor, max_ratio, up, per_second)

CREATE VIRTUAL TABLE bad USING laban(content=motions, label=emotion, options='[1]');
-- error: laban: options must be a JSON object, got array

CREATE VIRTUAL TABLE bad USING laban(content=motions, label=emotion, options='{"up":');
-- error: laban: options are not valid JSON: at byte 6: unexpected end of text

CREATE VIRTUAL TABLE k USING laban(content=motions, label=emotion);
-- error: laban: a laban table cannot be named "k": that is one of its columns

CREATE VIRTUAL TABLE bad USING laban(content=bad_data, label=emotion);
-- error: laban: the content table cannot be bad itself or its shadow tables

SELECT 'failed constructors leave no table behind', count(*) = 0 FROM sqlite_schema
 WHERE name LIKE 'bad%' OR name = 'k';

-- ---- a small table: ties, missing components, NULL labels and motions, label types ----
CREATE TABLE small(id INTEGER PRIMARY KEY, tag, m BLOB);

INSERT INTO small VALUES
    (3, 'sad', motion_synth('walk', 'sad', 1)),
    (7, 'happy', motion_synth('walk', 'happy', 1)),
    (10, 'sad', motion_synth('walk', 'sad', 1)),
    (12, 'angry', motion_select(motion_synth('walk', 'angry', 1),
        '["Hips","Spine","Chest","Neck","Head","UpperLeg_L","LowerLeg_L","Foot_L",' ||
        '"UpperLeg_R","LowerLeg_R","Foot_R"]')),
    (15, NULL, motion_synth('wave', 'neutral', 1)),
    (20, 1, motion_synth('knock', 'angry', 1)),
    (21, 'sad', NULL);

CREATE VIRTUAL TABLE small_laban USING laban(content=small, motion=m, label=tag);

SELECT group_concat(rowid) FROM small_laban;
-- expect: 3,7,10,12,15,20

SELECT group_concat(rowid || ':' || distance, ' ') FROM small_laban
 WHERE query = (SELECT m FROM small WHERE id = 10) AND k = 2;
-- expect: 3:0.0 10:0.0

SELECT group_concat(rowid || ':' || distance, ' ') FROM small_laban WHERE query = 10 AND k = 1;
-- expect: 3:0.0

SELECT 'a missing component is NULL in its column and NaN in the vector',
       WeightAll IS NULL AND WeightLHand IS NULL AND ShapeDirRHand IS NULL
       AND WeightTorso IS NOT NULL AND TimeHead IS NOT NULL
       AND (SELECT substr(hex(vector), 1, 8) FROM small_laban_data WHERE id = 12) = '0000C07F'
  FROM small_laban WHERE rowid = 12;

SELECT 'the statistics skip missing values', abs(json_extract(value, '$[0]') -
       (SELECT avg(WeightAll) FROM small_laban)) < 1e-9 * json_extract(value, '$[0]')
  FROM small_laban_info WHERE key = 'mean';

SELECT 'a row sharing no component with the query is not a candidate', count(*) = 0
  FROM small_laban WHERE query = 12 AND k = 5 AND components = '["WeightLHand"]';

SELECT 'missing components are skipped',
       abs(l.distance - abs((a.WeightTorso - b.WeightTorso) /
                            json_extract(s.value, '$[1]'))) < 1e-9
  FROM small_laban AS l, small_laban AS a, small_laban AS b, small_laban_info AS s
 WHERE l.query = 7 AND l.k = 10 AND l.components = '["WeightLHand","WeightTorso"]'
   AND l.rowid = 12 AND a.rowid = 7 AND b.rowid = 12 AND s.key = 'sd';

SELECT 'label = 1 matches the integer label', group_concat(rowid) = '20'
  FROM small_laban WHERE label = 1;

SELECT 'label = 1.0 matches it too (numbers compare numerically)', group_concat(rowid) = '20'
  FROM small_laban WHERE query = 3 AND label = 1.0 AND k = 5;

SELECT 'label = ''1'' does not (no comparison across types)', count(*) = 0
  FROM small_laban WHERE label = '1';

SELECT 'NULL labels never match', count(*) = 0 FROM small_laban WHERE label = NULL;

SELECT 'a NULL label is NULL in a scan', group_concat(rowid) = '15'
  FROM small_laban WHERE label IS NULL;

SELECT 'a NULL motion is not indexed, and check agrees', count(*) = 0
  FROM small_laban WHERE rowid = 21;

INSERT INTO small_laban(small_laban) VALUES('check');

UPDATE small SET m = x'00' WHERE id = 3;

INSERT INTO small_laban(small_laban) VALUES('rebuild');
-- error: laban: row 3 of small: not a valid motion: truncated: 1 bytes is shorter than the 32-byte header

INSERT INTO small_laban(small_laban, rowid) VALUES('refresh', 3);
-- error: laban: row 3 of small: not a valid motion: truncated: 1 bytes is shorter than the 32-byte header

UPDATE small SET m = 'text' WHERE id = 3;

INSERT INTO small_laban(small_laban, rowid) VALUES('refresh', 3);
-- error: laban: row 3 of small: the motion must be a BLOB, got text

INSERT INTO small_laban(small_laban) VALUES('check');
-- error: laban: 1 row is stale (first: rowid 3); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

UPDATE small SET m = NULL WHERE id = 3;
INSERT INTO small_laban(small_laban, rowid) VALUES('refresh', 3);

SELECT 'a motion set to NULL leaves the index on refresh', count(*) = 0
  FROM small_laban WHERE rowid = 3;

INSERT INTO small_laban(small_laban) VALUES('check');

-- ---- corrupt stored vectors: 'check' and every reader refuse them, naming the rowid ----
-- Each is written straight into the shadow table, as a damaged file or a stray UPDATE would
-- leave it; the generation is bumped too, so that this connection reloads its cached vectors.
-- A sound vector is a BLOB of 27 float32, each finite and >= 0 or the missing marker NaN
-- 0x7fc00000 (row 12 has some: the checks above pass with them).
CREATE TEMP TABLE sound AS SELECT id, laban_vector(m) AS v FROM small WHERE id IN (7, 10);

UPDATE small_laban_data SET vector = x'00' WHERE id = 7;
UPDATE small_laban_info SET value = value + 1 WHERE key = 'generation';

INSERT INTO small_laban(small_laban) VALUES('check');
-- error: laban: stored vector of rowid 7 is corrupt (1 bytes, expected 108); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

SELECT rowid FROM small_laban WHERE query = 10 AND k = 1;
-- error: laban: stored vector of rowid 7 is corrupt (1 bytes, expected 108); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

SELECT rowid FROM small_laban WHERE query = (SELECT m FROM small WHERE id = 10) AND radius = 0.5;
-- error: laban: stored vector of rowid 7 is corrupt (1 bytes, expected 108); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

SELECT count(*) FROM small_laban;
-- error: laban: stored vector of rowid 7 is corrupt (1 bytes, expected 108); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

SELECT laban_salient('small_laban');
-- error: laban_salient: index "small_laban": stored vector of rowid 7 is corrupt (1 bytes, expected 108); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

SELECT affect_generate('small_laban', (SELECT m FROM small WHERE id = 10), 'sad');
-- error: affect_generate: index "small_laban": stored vector of rowid 7 is corrupt (1 bytes, expected 108); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

SELECT affect_generate_explain('small_laban', (SELECT m FROM small WHERE id = 10), 'sad');
-- error: affect_generate_explain: index "small_laban": stored vector of rowid 7 is corrupt (1 bytes, expected 108); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

UPDATE small_laban_data SET vector = NULL WHERE id = 7;
UPDATE small_laban_info SET value = value + 1 WHERE key = 'generation';

INSERT INTO small_laban(small_laban) VALUES('check');
-- error: laban: stored vector of rowid 7 is corrupt (null, expected a BLOB of 108 bytes); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

SELECT rowid FROM small_laban WHERE query = 10 AND k = 1;
-- error: laban: stored vector of rowid 7 is corrupt (null, expected a BLOB of 108 bytes); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

SELECT laban_salient('small_laban');
-- error: laban_salient: index "small_laban": stored vector of rowid 7 is corrupt (null, expected a BLOB of 108 bytes); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

SELECT affect_generate('small_laban', (SELECT m FROM small WHERE id = 10), 'sad');
-- error: affect_generate: index "small_laban": stored vector of rowid 7 is corrupt (null, expected a BLOB of 108 bytes); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

-- random bytes of a wrong length, and of the right one
UPDATE small_laban_data SET vector = x'007580875D7F6AA995BC105165BBFBC47DC6A0F9107EDBF0AD2D863442661B486C84F9E540C21A3683BCD9D641E3712E4B58' WHERE id = 7;
UPDATE small_laban_info SET value = value + 1 WHERE key = 'generation';

INSERT INTO small_laban(small_laban) VALUES('check');
-- error: laban: stored vector of rowid 7 is corrupt (50 bytes, expected 108); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

SELECT rowid FROM small_laban WHERE query = 10 AND k = 1;
-- error: laban: stored vector of rowid 7 is corrupt (50 bytes, expected 108); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

SELECT laban_salient('small_laban');
-- error: laban_salient: index "small_laban": stored vector of rowid 7 is corrupt (50 bytes, expected 108); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

SELECT affect_generate('small_laban', (SELECT m FROM small WHERE id = 10), 'sad');
-- error: affect_generate: index "small_laban": stored vector of rowid 7 is corrupt (50 bytes, expected 108); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

UPDATE small_laban_data SET vector = x'367E8A829525E69BEECBC93C8672A1B785B84C528C5405233EAC0E2A8C68C3CEE03039BA5C30F9638AE76FF89082343E2D8E8F3C0E52D23A2FD9F556C5E99EF8EBDFD53083F2C978E6FA2249FA88E109CFD80AB1BCF186B69A6015F08330C63211629F0C0090B7803A114A65' WHERE id = 7;
UPDATE small_laban_info SET value = value + 1 WHERE key = 'generation';

INSERT INTO small_laban(small_laban) VALUES('check');
-- error: laban: stored vector of rowid 7 is corrupt (WeightAll is -2.03497191e-37, expected a finite number >= 0 or NaN 0x7fc00000 for missing); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

SELECT rowid FROM small_laban WHERE query = 10 AND k = 1;
-- error: laban: stored vector of rowid 7 is corrupt (WeightAll is -2.03497191e-37, expected a finite number >= 0 or NaN 0x7fc00000 for missing); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

SELECT laban_salient('small_laban');
-- error: laban_salient: index "small_laban": stored vector of rowid 7 is corrupt (WeightAll is -2.03497191e-37, expected a finite number >= 0 or NaN 0x7fc00000 for missing); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

SELECT affect_generate('small_laban', (SELECT m FROM small WHERE id = 10), 'sad');
-- error: affect_generate: index "small_laban": stored vector of rowid 7 is corrupt (WeightAll is -2.03497191e-37, expected a finite number >= 0 or NaN 0x7fc00000 for missing); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

-- an oversized zeroblob; two corrupt rows: the first is named, the others counted
UPDATE small_laban_data SET vector = zeroblob(1000000) WHERE id = 10;
UPDATE small_laban_info SET value = value + 1 WHERE key = 'generation';

INSERT INTO small_laban(small_laban) VALUES('check');
-- error: laban: stored vector of rowid 7 is corrupt (WeightAll is -2.03497191e-37, expected a finite number >= 0 or NaN 0x7fc00000 for missing), and 1 more is; run INSERT INTO small_laban(small_laban) VALUES('rebuild')

UPDATE small_laban_data SET vector = (SELECT v FROM sound WHERE id = 7) WHERE id = 7;

INSERT INTO small_laban(small_laban) VALUES('check');
-- error: laban: stored vector of rowid 10 is corrupt (1000000 bytes, expected 108); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

SELECT rowid FROM small_laban WHERE query = 7 AND k = 1;
-- error: laban: stored vector of rowid 10 is corrupt (1000000 bytes, expected 108); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

SELECT laban_salient('small_laban');
-- error: laban_salient: index "small_laban": stored vector of rowid 10 is corrupt (1000000 bytes, expected 108); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

SELECT affect_generate('small_laban', (SELECT m FROM small WHERE id = 7), 'sad');
-- error: affect_generate: index "small_laban": stored vector of rowid 10 is corrupt (1000000 bytes, expected 108); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

UPDATE small_laban_data SET vector = (SELECT v FROM sound WHERE id = 10) WHERE id = 10;

-- a NaN other than the missing marker, infinity, a negative value, text
UPDATE small_laban_data SET vector = CAST(x'0000C0FF' || substr((SELECT v FROM sound WHERE id = 7), 5) AS BLOB) WHERE id = 7;
UPDATE small_laban_info SET value = value + 1 WHERE key = 'generation';

SELECT 'the row is 108 bytes, NaN first', length(vector) = 108 AND hex(substr(vector, 1, 4)) = '0000C0FF'
  FROM small_laban_data WHERE id = 7;

INSERT INTO small_laban(small_laban) VALUES('check');
-- error: laban: stored vector of rowid 7 is corrupt (WeightAll is NaN 0xffc00000, expected a finite number >= 0 or NaN 0x7fc00000 for missing); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

SELECT rowid FROM small_laban WHERE query = 10 AND k = 1;
-- error: laban: stored vector of rowid 7 is corrupt (WeightAll is NaN 0xffc00000, expected a finite number >= 0 or NaN 0x7fc00000 for missing); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

SELECT laban_salient('small_laban');
-- error: laban_salient: index "small_laban": stored vector of rowid 7 is corrupt (WeightAll is NaN 0xffc00000, expected a finite number >= 0 or NaN 0x7fc00000 for missing); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

SELECT affect_generate('small_laban', (SELECT m FROM small WHERE id = 10), 'sad');
-- error: affect_generate: index "small_laban": stored vector of rowid 7 is corrupt (WeightAll is NaN 0xffc00000, expected a finite number >= 0 or NaN 0x7fc00000 for missing); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

UPDATE small_laban_data SET vector = CAST(substr((SELECT v FROM sound WHERE id = 7), 1, 36) || x'0000807F' || substr((SELECT v FROM sound WHERE id = 7), 41) AS BLOB) WHERE id = 7;
UPDATE small_laban_info SET value = value + 1 WHERE key = 'generation';

INSERT INTO small_laban(small_laban) VALUES('check');
-- error: laban: stored vector of rowid 7 is corrupt (TimeHead is inf, expected a finite number >= 0 or NaN 0x7fc00000 for missing); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

SELECT rowid FROM small_laban WHERE query = 10 AND k = 1;
-- error: laban: stored vector of rowid 7 is corrupt (TimeHead is inf, expected a finite number >= 0 or NaN 0x7fc00000 for missing); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

SELECT laban_salient('small_laban');
-- error: laban_salient: index "small_laban": stored vector of rowid 7 is corrupt (TimeHead is inf, expected a finite number >= 0 or NaN 0x7fc00000 for missing); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

UPDATE small_laban_data SET vector = CAST(x'000080BF' || substr((SELECT v FROM sound WHERE id = 7), 5) AS BLOB) WHERE id = 7;
UPDATE small_laban_info SET value = value + 1 WHERE key = 'generation';

INSERT INTO small_laban(small_laban) VALUES('check');
-- error: laban: stored vector of rowid 7 is corrupt (WeightAll is -1, expected a finite number >= 0 or NaN 0x7fc00000 for missing); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

SELECT rowid FROM small_laban WHERE query = 10 AND k = 1;
-- error: laban: stored vector of rowid 7 is corrupt (WeightAll is -1, expected a finite number >= 0 or NaN 0x7fc00000 for missing); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

UPDATE small_laban_data SET vector = CAST((SELECT v FROM sound WHERE id = 7) AS TEXT) WHERE id = 7;
UPDATE small_laban_info SET value = value + 1 WHERE key = 'generation';

INSERT INTO small_laban(small_laban) VALUES('check');
-- error: laban: stored vector of rowid 7 is corrupt (text, expected a BLOB of 108 bytes); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

SELECT laban_salient('small_laban');
-- error: laban_salient: index "small_laban": stored vector of rowid 7 is corrupt (text, expected a BLOB of 108 bytes); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

-- a corrupt vector of a row without a label is refused too (the queries read every row)
UPDATE small_laban_data SET vector = (SELECT v FROM sound WHERE id = 7) WHERE id = 7;
UPDATE small_laban_data SET vector = x'00' WHERE id = 15;
UPDATE small_laban_info SET value = value + 1 WHERE key = 'generation';

SELECT laban_salient('small_laban');
-- error: laban_salient: index "small_laban": stored vector of rowid 15 is corrupt (1 bytes, expected 108); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

INSERT INTO small_laban(small_laban) VALUES('rebuild');
INSERT INTO small_laban(small_laban) VALUES('check');

SELECT 'rebuild repairs the vectors', count(*) = 2 FROM small_laban_data JOIN sound USING (id)
 WHERE vector = v;

SELECT 'and the readers work again', count(*) = 2 FROM small_laban WHERE query = 10 AND k = 2;

-- ---- cache entries of _info ('check' validates each kind; the RMLR fit's in generate.sql) ----
INSERT INTO small_laban_info(key, value) VALUES('rmlr', x'00'), ('rmlr_key', 'x');

INSERT INTO small_laban(small_laban) VALUES('check');
-- error: laban: cache entry 'rmlr' is corrupt: its key "x" is not content:rows:seed:folds as laban_salient writes it; the next laban_salient or affect_generate on the index replaces it

UPDATE small_laban_info SET value = '0123456789abcdef:3:1:10' WHERE key = 'rmlr_key';

INSERT INTO small_laban(small_laban) VALUES('check');
-- error: laban: cache entry 'rmlr' is corrupt: it is not an RMLR fit (RMLR: truncated: 1 bytes is shorter than the 12-byte header); the next laban_salient or affect_generate on the index replaces it

UPDATE small_laban_info SET value = 'fit' WHERE key = 'rmlr';

INSERT INTO small_laban(small_laban) VALUES('check');
-- error: laban: cache entry 'rmlr' is corrupt: its value is text and its key text, expected a blob and text

DELETE FROM small_laban_info WHERE key = 'rmlr_key';

INSERT INTO small_laban(small_laban) VALUES('check');
-- error: laban: cache entry 'rmlr' is corrupt: small_laban_info has its row 'rmlr' but not 'rmlr_key'

DELETE FROM small_laban_info WHERE key = 'rmlr';
INSERT INTO small_laban(small_laban) VALUES('check');

-- ---- an empty index: no rows, no error ----
CREATE TABLE nomotions(id INTEGER PRIMARY KEY, tag, m BLOB);
CREATE VIRTUAL TABLE empty_laban USING laban(content=nomotions, motion=m, label=tag);

SELECT 'an empty index has no rows', count(*) = 0 FROM empty_laban;

SELECT 'k nearest of an empty index: none', count(*) = 0
  FROM empty_laban WHERE query = (SELECT m FROM small WHERE id = 10) AND k = 3;

SELECT 'a radius query of an empty index: none', count(*) = 0
  FROM empty_laban WHERE query = (SELECT m FROM small WHERE id = 10) AND label = 'sad'
   AND radius = 0.5 AND components = '["TimeAll"]';

SELECT rowid FROM empty_laban WHERE query = 10 AND k = 1;
-- error: laban: no row 10 in the index

SELECT 'its statistics: 0 rows, means null, sds 1',
       (SELECT value FROM empty_laban_info WHERE key = 'rows') = 0
   AND (SELECT json_extract(value, '$[0]') IS NULL FROM empty_laban_info WHERE key = 'mean')
   AND (SELECT json_extract(value, '$[26]') = 1 FROM empty_laban_info WHERE key = 'sd');

INSERT INTO empty_laban(empty_laban) VALUES('check');
INSERT INTO empty_laban(empty_laban) VALUES('rebuild');

DROP TABLE empty_laban;
DROP TABLE nomotions;

-- ---- shadow tables: protected, renamed, dropped ----
SELECT group_concat(type || ' ' || name, ', ') FROM
  (SELECT type, name FROM pragma_table_list WHERE name LIKE 'small\_laban%' ESCAPE '\'
   ORDER BY name);
-- expect: virtual small_laban, shadow small_laban_data, shadow small_laban_info

ALTER TABLE small_laban RENAME TO radius;
-- error: laban: a laban table cannot be named "radius": that is one of its columns

ALTER TABLE small_laban RENAME TO tiny;

SELECT group_concat(name, ' ') FROM (SELECT name FROM sqlite_schema
 WHERE name LIKE 'small\_laban%' ESCAPE '\' OR name LIKE 'tiny%' ORDER BY name);
-- expect: tiny tiny_data tiny_info

SELECT 'the renamed index answers', group_concat(rowid) = '7,10,12,15,20' FROM tiny;

SELECT group_concat(name, ' ') FROM pragma_table_xinfo('tiny') WHERE hidden <> 0;
-- expect: distance query k radius components tiny

INSERT INTO tiny(tiny) VALUES('rebuild');
INSERT INTO tiny(tiny) VALUES('check');

DROP TABLE tiny;

SELECT 'DROP TABLE removes the shadow tables', count(*) = 0 FROM sqlite_schema
 WHERE name LIKE 'tiny%';

-- without SQLITE_DBCONFIG_DEFENSIVE a shadow table can be dropped by hand; the index then says so
CREATE VIRTUAL TABLE broken USING laban(content=small, motion=m, label=tag);
DROP TABLE broken_info;

SELECT count(*) FROM broken;
-- error: laban: no such table: main.broken_info

DROP TABLE broken;

SELECT 'DROP TABLE works on a broken index', count(*) = 0 FROM sqlite_schema
 WHERE name LIKE 'broken%';
