-- generate.sql — SQL-level specification of affect generation (SCIENCE.md §5): laban_salient,
-- affect_generate, affect_generate_explain over a laban index of motion_synth.
-- Run by tests/sql/test_sql.c; see its header for the annotations. Generations and the RMLR fit
-- are "-- oom: skip" (seconds each); the argument checks run under fault injection.

CREATE TABLE motions(id INTEGER PRIMARY KEY, action TEXT, emotion TEXT, seed INTEGER, motion BLOB);
INSERT INTO motions(action, emotion, seed, motion)
SELECT a.value, e.value, k.value, motion_synth(a.value, e.value, k.value)
  FROM json_each('["knock","wave"]') AS a,
       json_each('["neutral","sad","angry"]') AS e,
       json_each('[1,2,3,4]') AS k;
CREATE VIRTUAL TABLE idx USING laban(content=motions, motion=motion, label=emotion);
CREATE TABLE plain(x);

-- ---- registration: not deterministic, direct-only (they read the index's tables) ----
SELECT group_concat(name || '/' || narg, ' ') FROM (
  SELECT DISTINCT name, narg FROM pragma_function_list
   WHERE name IN ('affect_generate', 'affect_generate_explain', 'laban_salient')
   ORDER BY name, narg);
-- expect: affect_generate/3 affect_generate/4 affect_generate_explain/3 affect_generate_explain/4 laban_salient/1 laban_salient/2

SELECT 'not deterministic, direct-only', count(*) = 6 FROM pragma_function_list
 WHERE name IN ('affect_generate', 'affect_generate_explain', 'laban_salient')
   AND (flags & 0x000000800) = 0 AND (flags & 0x000080000) <> 0;

-- ---- laban_salient: RMLR over the index, cached in idx_info ----
SELECT 'laban_salient: every label has salient components, every pair a set',
       json_valid(s) AND json_extract(s, '$.rows') = 24
   AND (SELECT count(*) FROM json_each(s, '$.salient')) = 3
   AND (SELECT count(*) FROM json_each(s, '$.pairs')) = 3
   AND json_extract(s, '$.alpha') BETWEEN 0.05 AND 1
  FROM (SELECT laban_salient('idx') AS s);
-- oom: skip

SELECT 'the fit is cached in the index''s info table', count(*) = 2
  FROM idx_info WHERE key IN ('rmlr', 'rmlr_key');
-- oom: skip

-- ---- generation with given components (no fit needed) ----
CREATE TABLE out AS
SELECT m.id, m.action, m.seed,
       affect_generate('idx', m.motion, 'sad', '{"method":"hmm_nn","components":["WeightAll","TimeAll","FlowAll"],"k":2}') AS sad,
       affect_generate('idx', m.motion, 'angry', '{"method":"hmm_nn","components":["WeightAll","TimeAll","FlowAll"],"k":2}') AS angry,
       m.motion AS source
  FROM motions AS m WHERE m.emotion = 'neutral' AND m.seed = 1;

SELECT 'output: the desired length, fps and skeleton',
       count(*) = 2 AND sum(motion_frames(sad) = motion_frames(source)) = 2
   AND sum(motion_fps(sad) = motion_fps(source)) = 2
   AND sum(json_extract(motion_info(angry), '$.names') = json_extract(motion_info(source), '$.names')) = 2
  FROM out;

-- The direction of the Laban change through the index, with the defaults (RMLR components,
-- ε = 0.1), over the 8 neutral motions: toward angry, WeightAll and TimeAll rise on average;
-- toward sad they stay below the angry results on average (source by source only 5 of 8 for
-- WeightAll). They do not fall below the neutral source
-- here (the jumps between state means outweigh the small synthetic knock's lower energy);
-- with neighbours of the same action they do (tests/core/test_generate.c), and on the real
-- corpus the mean shift toward sad is negative (sql/generate_eval.py, README).
CREATE TABLE dir AS
WITH g AS MATERIALIZED (
  SELECT m.id, t.value AS target, m.motion AS src, affect_generate('idx', m.motion, t.value) AS m
    FROM motions AS m, json_each('["sad","angry"]') AS t WHERE m.emotion = 'neutral')
SELECT id, target, laban_weight(src) AS w0, laban_time(src) AS t0, laban_weight(m) AS w,
       laban_time(m) AS t
  FROM g;
-- oom: skip

SELECT 'toward angry: WeightAll and TimeAll rise on average', avg(w) > avg(w0) AND avg(t) > avg(t0)
  FROM dir WHERE target = 'angry';

SELECT 'toward sad: below toward angry on average (WeightAll and TimeAll)',
       avg(s.w) < avg(a.w) AND avg(s.t) < avg(a.t)
  FROM dir AS s JOIN dir AS a ON a.id = s.id AND a.target = 'angry' WHERE s.target = 'sad';

SELECT 'deterministic',
       (SELECT affect_generate('idx', motion, 'sad', '{"method":"hmm_nn","components":["WeightAll","TimeAll"],"k":2}')
          FROM motions WHERE id = 1)
     = (SELECT affect_generate('idx', motion, 'sad', '{"method":"hmm_nn","components":["WeightAll","TimeAll"],"k":2}')
          FROM motions WHERE id = 1);
-- oom: skip

SELECT 'explain: source from the index, neighbours, Viterbi path of the desired length',
       json_valid(e) AND json_extract(e, '$.source.from') = 'index'
   AND json_extract(e, '$.source.label') = 'neutral'
   AND json_array_length(e, '$.neighbours.rows') = 3
   AND json_type(e, '$.neighbours.filled_to_min') = 'true'
   AND json_type(e, '$.neighbours.ranked_by_action') = 'true'
   AND json_array_length(e, '$.viterbi.path') = (SELECT motion_frames(motion) FROM motions WHERE id = 1)
  FROM (SELECT affect_generate_explain('idx', motion, 'sad', '{"method":"hmm_nn","components":["TimeAll"],"k":2}') AS e
          FROM motions WHERE id = 1);
-- oom: skip

SELECT 'automatic components (RMLR) and epsilon',
       json_extract(e, '$.components.chosen_by') = 'rmlr'
   AND json_extract(e, '$.neighbours.by') = 'epsilon'
   AND json_array_length(e, '$.neighbours.rows') >= 1
  FROM (SELECT affect_generate_explain('idx', motion, 'angry', '{"method":"hmm_nn"}') AS e FROM motions WHERE id = 1);
-- oom: skip

-- ---- the default method: transfer onto the desired motion ----
CREATE TABLE tr AS
SELECT m.id, m.action, m.motion AS src,
       affect_generate('idx', m.motion, 'angry', '{"strength":0}') AS s0,
       affect_generate('idx', m.motion, 'angry', '{"strength":0.5}') AS s05,
       affect_generate('idx', m.motion, 'angry') AS s1,
       affect_generate('idx', m.motion, 'angry', '{"strength":2}') AS s2,
       affect_generate('idx', m.motion, 'sad') AS sad,
       affect_generate_explain('idx', m.motion, 'angry') AS e
  FROM motions AS m WHERE m.emotion = 'neutral' AND m.seed IN (1, 2);
-- oom: skip

SELECT 'transfer: the desired length, fps and joints; strength 0 is the source''s rigid form',
       count(*) = 4 AND sum(motion_frames(s1) = motion_frames(src)) = 4
   AND sum(motion_fps(s2) = motion_fps(src)) = 4
   AND sum(json_extract(motion_info(s1), '$.names') = json_extract(motion_info(src), '$.names')) = 4
   AND sum(motion_dtw(s0, src) < 0.01) = 4
  FROM tr;

SELECT 'transfer: every output is a rigid skeleton (bone lengths vary by at most 1e-4)',
       max(json_extract(motion_info(s2), '$.bone_variation')) <= 1e-4
   AND max(json_extract(motion_info(sad), '$.bone_variation')) <= 1e-4
  FROM tr;

SELECT 'transfer: toward angry WeightAll rises with the strength, motion by motion',
       sum(laban_weight(s0) < laban_weight(s05) AND laban_weight(s05) < laban_weight(s1)
           AND laban_weight(s1) < laban_weight(s2)) = 4
  FROM tr;

SELECT 'transfer: toward sad below toward angry (WeightAll), motion by motion',
       sum(laban_weight(sad) < laban_weight(s1)) = 4 FROM tr;

SELECT 'transfer: the action stays (closer to its source than to the other action''s source)',
       count(*) = 8 AND sum(motion_dtw(a.s1, a.src) < motion_dtw(a.s1, b.src)) = 8
  FROM tr AS a JOIN tr AS b ON b.action <> a.action;
-- oom: skip

SELECT 'explain: method, strength, three donor pairs of neutral → angry, the change applied',
       json_extract(e, '$.method') = 'transfer' AND json_extract(e, '$.strength') = 1
   AND json_array_length(e, '$.pairs') = 3
   AND json_extract(e, '$.pairs[0].from.label') = 'neutral'
   AND json_extract(e, '$.pairs[2].to.label') = 'angry'
   AND json_extract(e, '$.change.joints') > 10
   AND json_extract(e, '$.change.amplitude_ratios[1]') > 1
   AND json_extract(e, '$.laban_change.WeightAll') > 0
   AND json_type(e, '$.contacts.kept') = 'true'
  FROM tr;

-- (on these synthetic gestures a wave's nearest angry candidates are sometimes all knocks)
SELECT 'donor pairs show one action in both emotions (pairing "action", the default): 10 of 12',
       count(*) = 12 AND sum(a.action = b.action) >= 10
  FROM tr, json_each(tr.e, '$.pairs') AS p
  JOIN motions AS a ON a.id = json_extract(p.value, '$.from.rowid')
  JOIN motions AS b ON b.id = json_extract(p.value, '$.to.rowid');

SELECT 'pair_by names a content column: pairs of one action, the same values',
       (SELECT count(*) FROM json_each(e, '$.pairs') AS p
          JOIN motions AS a ON a.id = json_extract(p.value, '$.from.rowid')
          JOIN motions AS b ON b.id = json_extract(p.value, '$.to.rowid')
         WHERE a.action = b.action) = 3
  FROM (SELECT affect_generate_explain('idx', motion, 'sad',
                 '{"pair_by":"action","pairing":"laban"}') AS e FROM motions WHERE id = 1);
-- oom: skip

SELECT affect_generate('idx', (SELECT motion FROM motions WHERE id = 1), 'sad', '{"pair_by":"nope"}');
-- error: affect_generate: option "pair_by": "nope" is not a column of the content table "motions"

SELECT affect_generate('idx', (SELECT motion FROM motions WHERE id = 1), 'sad', '{"pairing":"dtw"}');
-- error: affect_generate: option "pairing" must be one of "action", "laban", got "dtw"

SELECT affect_generate('idx', (SELECT motion FROM motions WHERE id = 1), 'sad', '{"amplitude":"speed"}');
-- error: affect_generate: option "amplitude" must be one of "velocity", "displacement", got "speed"

SELECT 'deterministic (the same bytes)',
       (SELECT affect_generate('idx', motion, 'sad', '{"pairs":2}') FROM motions WHERE id = 1)
     = (SELECT affect_generate('idx', motion, 'sad', '{"pairs":2}') FROM motions WHERE id = 1);
-- oom: skip

-- A position-only motion's rigid form (inverse kinematics) is what strength 0 returns; the
-- root (Hips) is where it is there, frame by frame, and within 1 cm of the source's.
SELECT 'a walk keeps its root path, frame by frame',
       (SELECT group_concat(x || ',' || y || ',' || z) FROM motion_points(g) WHERE name = 'Hips')
     = (SELECT group_concat(x || ',' || y || ',' || z) FROM motion_points(g0) WHERE name = 'Hips')
   AND (SELECT max(abs(a.x - b.x) + abs(a.y - b.y) + abs(a.z - b.z))
          FROM motion_points(g) AS a JOIN motion_points(src) AS b USING (frame, joint)
         WHERE a.name = 'Hips') < 0.01
  FROM (SELECT motion_synth('walk', 'neutral', 9) AS src),
       (SELECT affect_generate('idx', motion_synth('walk', 'neutral', 9), 'sad') AS g),
       (SELECT affect_generate('idx', motion_synth('walk', 'neutral', 9), 'sad', '{"strength":0}') AS g0);
-- oom: skip

-- the donors (position-only here) go through inverse kinematics once: the second call reads
-- their skeletal forms from the function's cache and must give the bytes of the first
SELECT 'transfer: the cached skeletal forms of the donors give the same bytes', a = b
  FROM (SELECT affect_generate('idx', motion_synth('walk', 'neutral', 11), 'angry') AS a),
       (SELECT affect_generate('idx', motion_synth('walk', 'neutral', 11), 'angry') AS b);
-- oom: skip

SELECT affect_generate('idx', (SELECT motion FROM motions WHERE id = 1), 'sad', '{"strength":2.5}');
-- error: affect_generate: option strength must be between 0 and 2

SELECT affect_generate('idx', (SELECT motion FROM motions WHERE id = 1), 'sad', '{"pairs":0}');
-- error: affect_generate: option "pairs" must be from 1 to 64, got 0

SELECT affect_generate('idx', (SELECT motion FROM motions WHERE id = 1), 'sad', '{"bands":[3]}');
-- error: affect_generate: option "bands" must be an array of two frequencies in Hz, [low, high]

SELECT affect_generate('idx', (SELECT motion FROM motions WHERE id = 1), 'sad', '{"bands":[3,1]}');
-- error: affect_generate: option band edges must satisfy 0 < low < high (Hz)

SELECT affect_generate('idx', (SELECT motion FROM motions WHERE id = 1), 'sad', '{"max_ratio":0.5}');
-- error: affect_generate: option max_ratio must be a finite number of at least 1

SELECT affect_generate('idx', (SELECT motion FROM motions WHERE id = 1), 'sad', '{"method":"spectral"}');
-- error: affect_generate: option "method" must be one of "transfer", "hmm_nn", got "spectral"

SELECT affect_generate('idx', (SELECT motion FROM motions WHERE id = 1), 'sad', '{"k":3}');
-- error: affect_generate: option "k" applies to {"method":"hmm_nn"} only

SELECT affect_generate('idx', (SELECT motion FROM motions WHERE id = 1), 'sad', '{"method":"hmm_nn","strength":1}');
-- error: affect_generate: option "strength" applies to {"method":"transfer"} only

-- ---- NULL and errors ----
SELECT affect_generate('idx', NULL, 'sad') IS NULL;
-- expect: 1

SELECT affect_generate('plain', (SELECT motion FROM motions WHERE id = 1), 'sad');
-- error: affect_generate: "plain" is not a laban table (CREATE VIRTUAL TABLE plain USING laban(…))

-- the index's format is checked by the one reader of its tables (vt_laban.h), as its queries
-- check it
UPDATE idx_info SET value = '2' WHERE key = 'format';
SELECT affect_generate('idx', (SELECT motion FROM motions WHERE id = 1), 'sad');
-- error: affect_generate: index "idx": idx_info has format "2"; this version reads format 1

UPDATE idx_info SET value = '1' WHERE key = 'format';

-- a table whose name holds "USING laban(" is not an index
CREATE TABLE "fake USING laban(" (x);
CREATE TABLE "fake USING laban(_info"(key TEXT PRIMARY KEY, value);
INSERT INTO "fake USING laban(_info"
VALUES ('format', '1'), ('content', 'motions'), ('motion', 'motion');
SELECT affect_generate('fake USING laban(', (SELECT motion FROM motions WHERE id = 1), 'sad');
-- error: affect_generate: "fake USING laban(" is not a laban table (CREATE VIRTUAL TABLE fake USING laban( USING laban(…))

DROP TABLE "fake USING laban(";
DROP TABLE "fake USING laban(_info";

SELECT affect_generate('idx', (SELECT motion FROM motions WHERE id = 1), 'happy', '{"components":["TimeAll"]}');
-- error: affect_generate: target label "happy": no motion of "idx" has this label (labels: angry, neutral, sad)

SELECT affect_generate('idx', (SELECT motion FROM motions WHERE id = 1), 'sad', '{"method":"hmm_nn","epsilon":2}');
-- error: affect_generate: option "epsilon" must be in (0, 1] (a fraction of the distance to the furthest target motion)

SELECT affect_generate('idx', (SELECT motion FROM motions WHERE id = 1), 'sad', '{"components":["Weight"]}');
-- error: affect_generate: option "components": "Weight" is not a Laban component name (laban_names())

SELECT affect_generate('idx', (SELECT motion FROM motions WHERE id = 1), 'sad', '{"source_label":"x","components":["TimeAll"]}');
-- error: affect_generate: source_label "x": no motion of "idx" has this label (labels: angry, neutral, sad)

SELECT affect_generate('idx', (SELECT motion FROM motions WHERE id = 1), 'sad', '{"method":"hmm_nn","render":"smooth","k":1,"components":["TimeAll"]}');
-- error: affect_generate: option "render" must be one of "steps", "linear", got "smooth"

SELECT affect_generate('idx', (SELECT motion FROM motions WHERE id = 1), 'sad', '{"method":"hmm_nn","keep_path":1,"k":1,"components":["TimeAll"]}');
-- error: affect_generate: option "keep_path" must be true or false, got number

SELECT affect_generate('idx', (SELECT motion FROM motions WHERE id = 1), 'sad', '{"method":"hmm_nn","copies":5000,"k":1,"components":["TimeAll"]}');
-- error: affect_generate: copies must be at most 1000, got 5000
-- oom: skip

-- ---- motion_dtw: the DTW distance that judges generated motions ----
SELECT 'motion_dtw is deterministic and direct-use', count(*) = 1 FROM pragma_function_list
 WHERE name = 'motion_dtw' AND narg = 2 AND (flags & 0x000000800) <> 0;

SELECT 'zero to itself, symmetric, positive between different motions',
       motion_dtw(a.motion, a.motion) = 0
   AND motion_dtw(a.motion, b.motion) = motion_dtw(b.motion, a.motion)
   AND motion_dtw(a.motion, b.motion) > 0
  FROM motions AS a, motions AS b WHERE a.id = 1 AND b.id = 2;

SELECT 'linear rendering and keep_path false give other motions of the same shape',
       motion_frames(l) = motion_frames(src) AND l <> s AND p <> s
  FROM (SELECT motion AS src,
               affect_generate('idx', motion, 'sad', '{"method":"hmm_nn","components":["TimeAll"],"k":2,"render":"steps"}') AS s,
               affect_generate('idx', motion, 'sad', '{"method":"hmm_nn","components":["TimeAll"],"k":2,"render":"linear"}') AS l,
               affect_generate('idx', motion, 'sad', '{"method":"hmm_nn","components":["TimeAll"],"k":2,"keep_path":false}') AS p
          FROM motions WHERE id = 1);
-- oom: skip

SELECT 'a generated motion keeps more of its path with copies = 2 than with 0',
       motion_dtw(affect_generate('idx', m.motion, 'sad', '{"method":"hmm_nn","components":["TimeAll"],"k":2,"copies":2}'), m.motion)
     < motion_dtw(affect_generate('idx', m.motion, 'sad', '{"method":"hmm_nn","components":["TimeAll"],"k":2,"copies":0}'), m.motion)
  FROM motions AS m WHERE m.id = 1;
-- oom: skip

SELECT 'NULL in, NULL out', motion_dtw(NULL, motion) IS NULL AND motion_dtw(motion, NULL) IS NULL
  FROM motions WHERE id = 1;

SELECT motion_dtw(x'00', motion) FROM motions WHERE id = 1;
-- error: motion_dtw: argument 1 is not a valid motion: truncated: 1 bytes is shorter than the 32-byte header

SELECT motion_dtw(motion, 'text') FROM motions WHERE id = 1;
-- error: motion_dtw: argument 2 must be a motion BLOB, got text

SELECT motion_dtw(motion, motion_select(motion, '["Hips","Spine"]')) FROM motions WHERE id = 1;
-- error: motion_dtw: the motions have different joint names

SELECT 'explain reports how the output was drawn',
       json_extract(e, '$.output') = '{"render":"linear","keep_path":false,"cutoff_hz":2,"covariance_scale":1}'
  FROM (SELECT affect_generate_explain('idx', motion, 'sad',
          '{"method":"hmm_nn","components":["TimeAll"],"k":2,"render":"linear","keep_path":false,"cutoff_hz":2}') AS e
          FROM motions WHERE id = 1);
-- oom: skip

-- ---- laban_salient: folds are part of the cache key; threads change only the time ----
-- (the 4-fold fit in between replaces both caches, so the last call fits again)
CREATE TABLE fits AS SELECT 'threads 2' AS k, laban_salient('idx', '{"folds":5,"threads":2}') AS s;
INSERT INTO fits SELECT 'folds 4', laban_salient('idx', '{"folds":4}');
INSERT INTO fits SELECT 'threads 1', laban_salient('idx', '{"folds":5}');
-- oom: skip

SELECT 'the fit with 2 threads is the fit with 1, and the stored key names the folds',
       (SELECT s FROM fits WHERE k = 'threads 2') = (SELECT s FROM fits WHERE k = 'threads 1')
   AND (SELECT value FROM idx_info WHERE key = 'rmlr_key') LIKE '%:24:1:5';

CREATE TABLE key_before AS SELECT value AS k FROM idx_info WHERE key = 'rmlr_key';
INSERT INTO idx(idx) VALUES('rebuild');
SELECT 'a rebuild that changes nothing keeps the stored fit, under the same key',
       (SELECT value FROM idx_info WHERE key = 'rmlr_key') = (SELECT k FROM key_before)
   AND (SELECT typeof(value) FROM idx_info WHERE key = 'rmlr') = 'blob'
   AND laban_salient('idx', '{"folds":5}') = (SELECT s FROM fits WHERE k = 'threads 1');

-- ---- a cached fit is used only for the index it was fitted on (regression: a laban index
-- dropped and created again under the same name over more labels, a changed label, or a
-- copied _info row made affect_generate read past the old fit's arrays) ----
CREATE TABLE more AS SELECT * FROM motions;
INSERT INTO more(id, action, emotion, seed, motion)
SELECT 100 + k.value, 'wave', 'happy', k.value, motion_synth('wave', 'happy', k.value)
  FROM json_each('[1,2,3,4]') AS k;
SELECT 'the old index''s fit is cached', json_extract(laban_salient('idx'), '$.rows') = 24;
-- oom: skip
DROP TABLE idx;
CREATE VIRTUAL TABLE idx USING laban(content=more, motion=motion, label=emotion);
SELECT 'recreated over 4 labels: refitted, 4 labels and 6 pairs',
       (SELECT count(*) FROM json_each(s, '$.salient')) = 4
   AND (SELECT count(*) FROM json_each(s, '$.pairs')) = 6 AND json_extract(s, '$.rows') = 28
  FROM (SELECT laban_salient('idx') AS s);
-- oom: skip

SELECT 'generation toward the new label works', motion_frames(g) = motion_frames(src)
  FROM (SELECT motion AS src, affect_generate('idx', motion, 'happy') AS g FROM more WHERE id = 1);
-- oom: skip

UPDATE more SET emotion = 'glad' WHERE emotion = 'happy';
INSERT INTO idx(idx) VALUES('rebuild');
SELECT 'a changed label: refitted under the new label',
       json_extract(s, '$.salient.glad') IS NOT NULL AND json_extract(s, '$.salient.happy') IS NULL
  FROM (SELECT laban_salient('idx') AS s);
-- oom: skip

-- 'check' validates the stored fit: sound, and of the index's shape when its key names the
-- index's rows
INSERT INTO idx(idx) VALUES('check');

CREATE VIRTUAL TABLE idx3 USING laban(content=motions, motion=motion, label=emotion);
INSERT OR REPLACE INTO idx3_info(key, value)
SELECT key, value FROM idx_info WHERE key IN ('rmlr', 'rmlr_key');
-- a fit of other rows is not corrupt, only unused
INSERT INTO idx3(idx3) VALUES('check');
SELECT 'a fit copied from another index is not used: 3 labels, 24 rows',
       (SELECT count(*) FROM json_each(s, '$.salient')) = 3 AND json_extract(s, '$.rows') = 24
  FROM (SELECT laban_salient('idx3') AS s);
-- oom: skip
INSERT INTO idx3(idx3) VALUES('check');

-- idx3's fit (3 labels, 24 rows) under idx's current key (4 labels, 28 rows); laban_salient's
-- own cache holds idx3's fit, so the stored one is read (with fewer classes than the index's
-- labels it was read past its arrays)
UPDATE idx_info SET value = (SELECT value FROM idx3_info WHERE key = 'rmlr') WHERE key = 'rmlr';
INSERT INTO idx(idx) VALUES('check');
-- error: laban: cache entry 'rmlr' is corrupt: the fit has 24 rows, its key says 28; the next laban_salient or affect_generate on the index replaces it
SELECT 'a fit of another shape under this index''s key is not used either: 4 labels, 28 rows',
       (SELECT count(*) FROM json_each(s, '$.salient')) = 4 AND json_extract(s, '$.rows') = 28
  FROM (SELECT laban_salient('idx') AS s);
-- oom: skip
INSERT INTO idx(idx) VALUES('check');

-- a fit cached before the RMLR fit had a header (version 1: a version byte 1, then the body
-- that version 2 keeps between its 20-byte header and its 8-byte checksum) is still read
SELECT 'the stored fit is version 2 (magic AFRL)', substr(value, 1, 4) = CAST('AFRL' AS BLOB)
  FROM idx3_info WHERE key = 'rmlr';
UPDATE idx3_info SET value = CAST(x'01' || substr(value, 21, length(value) - 28) AS BLOB)
 WHERE key = 'rmlr';
INSERT INTO idx3(idx3) VALUES('check');
UPDATE idx3_info SET value = CAST(value || x'00' AS BLOB) WHERE key = 'rmlr';
INSERT INTO idx3(idx3) VALUES('check');
-- error: laban: cache entry 'rmlr' is corrupt: 1 bytes follow the RMLR fit; the next laban_salient or affect_generate on the index replaces it
UPDATE idx3_info SET value = substr(value, 1, 100) WHERE key = 'rmlr';
INSERT INTO idx3(idx3) VALUES('check');
-- error: laban: cache entry 'rmlr' is corrupt: it is not an RMLR fit (RMLR: truncated in the lambdas (offset 38)); the next laban_salient or affect_generate on the index replaces it

-- ---- an empty index: a clear error (regression: NULL was passed to memcpy) ----
CREATE TABLE nomotions(id INTEGER PRIMARY KEY, emotion TEXT, motion BLOB);
CREATE VIRTUAL TABLE idx0 USING laban(content=nomotions, motion=motion, label=emotion);

SELECT laban_salient('idx0');
-- error: laban_salient: index "idx0" is empty: it holds no row with a label

SELECT affect_generate('idx0', (SELECT motion FROM motions WHERE id = 1), 'sad');
-- error: affect_generate: index "idx0" is empty: it holds no row with a label

SELECT affect_generate('idx0', (SELECT motion FROM motions WHERE id = 1), 'sad', '{"method":"hmm_nn","components":["TimeAll"],"k":2}');
-- error: affect_generate: index "idx0" is empty: it holds no row with a label

SELECT affect_generate_explain('idx0', (SELECT motion FROM motions WHERE id = 1), 'sad');
-- error: affect_generate_explain: index "idx0" is empty: it holds no row with a label

SELECT 'its k-nearest query gives no rows', count(*) = 0
  FROM idx0 WHERE query = (SELECT motion FROM motions WHERE id = 1) AND k = 3;

-- rows without labels: empty for generation as well
INSERT INTO nomotions(emotion, motion) SELECT NULL, motion FROM motions WHERE id <= 2;
INSERT INTO idx0(idx0) VALUES('rebuild');

SELECT laban_salient('idx0');
-- error: laban_salient: index "idx0" is empty: it holds no row with a label

SELECT affect_generate('idx0', (SELECT motion FROM motions WHERE id = 1), 'sad');
-- error: affect_generate: index "idx0" is empty: it holds no row with a label

SELECT 'its k-nearest query still finds the unlabelled rows', count(*) = 2
  FROM idx0 WHERE query = (SELECT motion FROM motions WHERE id = 1) AND k = 3;

SELECT laban_salient('idx', '{"threads":0}');
-- error: laban_salient: option "threads" must be from 1 to 64, got 0

SELECT affect_generate('idx', (SELECT motion FROM motions WHERE id = 1), 'sad', '{"threads":65}');
-- error: affect_generate: option "threads" must be from 1 to 64, got 65
