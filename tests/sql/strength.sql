-- strength.sql — SQL-level specification of emotion strength by relative attributes
-- (SCIENCE.md §6): strength_train, affect_strength, strength_synthesize, strength_edit,
-- strength_info, motion_keyframes, rank_train, rank_score.
-- Run by tests/sql/test_sql.c; see its header for the annotations. Models are trained once by
-- CREATE TABLE … AS (run once, also in the --oom mode); table-wide checks are "-- oom: skip";
-- a small model covers every function under fault injection.

-- synthetic motions of known anger intensity: 2 actions × 3 intensities × 6 seeds
CREATE TABLE s(action TEXT, lvl REAL, seed INTEGER, m BLOB);
INSERT INTO s
SELECT a.value, i.value, k.value, motion_synth(a.value, 'angry', k.value, json_object('intensity', i.value))
  FROM json_each('["knock","wave"]') AS a, json_each('[0.2,0.8,1.4]') AS i,
       json_each('[1,2,3,4,5,6]') AS k;

-- ---- registration ----
SELECT group_concat(name || '/' || narg || '/' || type, ' ') FROM (
  SELECT DISTINCT name, narg, type FROM pragma_function_list
   WHERE name LIKE 'strength\_%' ESCAPE '\' OR name LIKE 'rank\_%' ESCAPE '\'
      OR name IN ('affect_strength', 'motion_keyframes') ORDER BY name, narg);
-- expect: affect_strength/2/s motion_keyframes/1/s motion_keyframes/2/s rank_score/2/s rank_train/2/a rank_train/3/a strength_edit/3/s strength_edit/4/s strength_info/1/s strength_synthesize/2/s strength_synthesize/3/s strength_train/2/a strength_train/3/a

SELECT 'the strength functions are deterministic and innocuous', count(*) = 13 FROM pragma_function_list
 WHERE (name LIKE 'strength\_%' ESCAPE '\' OR name LIKE 'rank\_%' ESCAPE '\'
        OR name IN ('affect_strength', 'motion_keyframes'))
   AND (flags & 0x000000800) <> 0 AND (flags & 0x000200000) <> 0;

-- ---- models: seeds 1–4 train, 5–6 are held out ----
-- ('both': both actions, the default features, the recognizer's Fisher representation; 'lab'
-- the same motions ranked by the Laban vector; 'kf' by keyframe features, which synthesis and
-- editing need; 'blocks': both the keyframe and the Laban block)
CREATE TABLE models AS
SELECT 'both' AS name, strength_train(m, lvl, '{"pca_dims":10}') AS r FROM s WHERE seed <= 4
UNION ALL
SELECT 'lab', strength_train(m, lvl, '{"pca_dims":10,"features":"laban"}') FROM s WHERE seed <= 4
UNION ALL
SELECT 'kf', strength_train(m, lvl, '{"pca_dims":10,"features":"keyframes"}') FROM s WHERE seed <= 4
UNION ALL
SELECT 'blocks', strength_train(m, lvl, '{"pca_dims":10,"features":"both"}') FROM s WHERE seed <= 4 AND action = 'knock'
UNION ALL
SELECT 'knock', strength_train(m, lvl, '{"pca_dims":10,"features":"keyframes"}') FROM s WHERE seed <= 4 AND action = 'knock'
UNION ALL
SELECT 'content', strength_train(m, json_object('label', CASE lvl WHEN 0.2 THEN 'mild' WHEN 0.8 THEN 'medium' ELSE 'strong' END, 'content', action),
                                 '{"order":["mild","medium","strong"],"pairs":"same_content","pca_dims":0,"keyframes":6,"regression":"local_linear"}')
  FROM s WHERE seed <= 4
UNION ALL
SELECT 'small', strength_train(m, lvl, '{"pca_dims":3,"keyframes":4,"fraction":0.5,"seed":2,"C":0.5,"features":"keyframes"}') FROM s WHERE seed <= 2 AND action = 'wave'
UNION ALL
SELECT 'small_laban', strength_train(m, lvl, '{"pca_dims":3,"keyframes":4,"features":"laban"}') FROM s WHERE seed <= 2 AND action = 'wave'
UNION ALL
SELECT 'small_fisher', strength_train(m, lvl, '{"pca_dims":3,"keyframes":4,"descriptors":"none"}') FROM s WHERE seed <= 2 AND action = 'wave'
UNION ALL
SELECT 'small_both', strength_train(m, lvl, '{"pca_dims":3,"keyframes":4,"features":"both"}') FROM s WHERE seed <= 2 AND action = 'wave';

SELECT 'every model trained', count(*) = 10 AND min(length(r)) > 100 FROM models;

-- affect_strength keeps its last model per connection: calls that alternate two models (one
-- function, so one cache) score as each model alone
SELECT 'alternating models score as each alone', count(*) = 8 AND sum(alt = own) = 8
       AND sum(alt <> other) = 8
  FROM (SELECT affect_strength(CASE WHEN k % 2 THEN b ELSE c END, m) AS alt,
               CASE WHEN k % 2 THEN affect_strength(b, m) ELSE affect_strength(c, m) END AS own,
               CASE WHEN k % 2 THEN affect_strength(c, m) ELSE affect_strength(b, m) END AS other
          FROM (SELECT rowid AS k, m FROM s WHERE seed > 4 LIMIT 8),
               (SELECT r AS b FROM models WHERE name = 'both'),
               (SELECT r AS c FROM models WHERE name = 'small'));
-- oom: skip

-- ranking accuracy on the held-out motions' pairs of one action (the default: the Fisher
-- representation)
SELECT 'held-out pair accuracy ' || avg(a.sc > b.sc), avg(a.sc > b.sc) >= 0.9
  FROM (SELECT action, lvl, affect_strength((SELECT r FROM models WHERE name = 'both'), m) AS sc FROM s WHERE seed > 4) AS a
  JOIN (SELECT action, lvl, affect_strength((SELECT r FROM models WHERE name = 'both'), m) AS sc FROM s WHERE seed > 4) AS b
    ON a.action = b.action AND a.lvl > b.lvl;
-- oom: skip

SELECT 'keyframe features: held-out pair accuracy ' || avg(a.sc > b.sc), avg(a.sc > b.sc) >= 0.9
  FROM (SELECT action, lvl, affect_strength((SELECT r FROM models WHERE name = 'kf'), m) AS sc FROM s WHERE seed > 4) AS a
  JOIN (SELECT action, lvl, affect_strength((SELECT r FROM models WHERE name = 'kf'), m) AS sc FROM s WHERE seed > 4) AS b
    ON a.action = b.action AND a.lvl > b.lvl;
-- oom: skip

SELECT 'both feature blocks: held-out pair accuracy ' || avg(a.sc > b.sc), avg(a.sc > b.sc) >= 0.9
  FROM (SELECT action, lvl, affect_strength((SELECT r FROM models WHERE name = 'blocks'), m) AS sc FROM s WHERE seed > 4 AND action = 'knock') AS a
  JOIN (SELECT action, lvl, affect_strength((SELECT r FROM models WHERE name = 'blocks'), m) AS sc FROM s WHERE seed > 4 AND action = 'knock') AS b
    ON a.action = b.action AND a.lvl > b.lvl;
-- oom: skip

SELECT 'same-content pairs, no PCA: held-out accuracy ' || avg(a.sc > b.sc), avg(a.sc > b.sc) >= 0.9
  FROM (SELECT action, lvl, affect_strength((SELECT r FROM models WHERE name = 'content'), m) AS sc FROM s WHERE seed > 4) AS a
  JOIN (SELECT action, lvl, affect_strength((SELECT r FROM models WHERE name = 'content'), m) AS sc FROM s WHERE seed > 4) AS b
    ON a.action = b.action AND a.lvl > b.lvl;
-- oom: skip

-- ---- determinism ----
SELECT 'training twice gives identical BLOBs',
       (SELECT strength_train(m, lvl, '{"pca_dims":10}') FROM s WHERE seed <= 4) = (SELECT r FROM models WHERE name = 'both');
-- oom: skip

-- ---- strength_info ----
SELECT json_extract(strength_info(r), '$.motions') || ' ' || json_extract(strength_info(r), '$.keyframes') || ' ' ||
       json_extract(strength_info(r), '$.pca.dims') || ' ' || json_extract(strength_info(r), '$.ranker.ordered_pairs') || ' ' ||
       json_extract(strength_info(r), '$.ranker.similar_pairs') || ' ' || json_array_length(strength_info(r), '$.levels')
  FROM models WHERE name = 'both';
-- expect: 24 13 10 192 84 3

SELECT group_concat(name || ' ' || json_extract(i, '$.version') || ' ' || json_extract(i, '$.ranker.features') || ' ' ||
       json_extract(i, '$.ranker.dims') || ' ' || json_extract(i, '$.ranker.loss') || ' ' ||
       coalesce(json_extract(i, '$.ranker.keyframe_weight') > 0, '-'), '; ')
  FROM (SELECT name, strength_info(r) AS i FROM models WHERE name IN ('both', 'kf', 'blocks', 'lab') ORDER BY name);
-- expect: blocks 2 both 37 mean 1; both 3 fisher 2451 sum -; kf 1 keyframes 10 sum -; lab 2 laban 27 mean -

-- Fisher features: the recognizer's descriptors (the kinematic summaries by default, or none:
-- the Fisher scores alone, 3 classes × 810 here), and the C given, not cross-validated
SELECT group_concat(name || ' ' || json_extract(i, '$.ranker.descriptors') || ' ' || json_extract(i, '$.ranker.dims') || ' '
                    || json_extract(i, '$.ranker.C_cross_validated'), '; ')
  FROM (SELECT name, strength_info(r) AS i FROM models WHERE name IN ('both', 'small_fisher') ORDER BY name);
-- expect: both kinematics 2451 0; small_fisher none 2430 0

-- C: chosen by the inner cross-validation with Laban features unless given; keyframes: as given
SELECT json_extract(strength_info(r), '$.ranker.C_cross_validated') AND json_extract(strength_info(r), '$.ranker.C') IN (0.01, 0.1, 1, 10, 100)
  FROM models WHERE name = 'lab';
-- expect: 1

SELECT group_concat(json_extract(strength_info(r), '$.ranker.C_cross_validated') || ' ' || json_extract(strength_info(r), '$.ranker.C'), '; ')
  FROM (SELECT r FROM models WHERE name IN ('small', 'kf') ORDER BY name);
-- expect: 0 1; 0 0.5

SELECT 'info: training accuracy, converged, levels in order, a regression chosen',
       json_extract(i, '$.ranker.training_accuracy') >= 0.95 AND json_extract(i, '$.ranker.converged')
       AND json_extract(i, '$.levels[0].strength') < json_extract(i, '$.levels[1].strength')
       AND json_extract(i, '$.levels[1].strength') < json_extract(i, '$.levels[2].strength')
       AND json_extract(i, '$.levels[0].label') = '0.2'
       AND json_extract(i, '$.regression.method') IN ('kernel_ridge', 'local_linear')
       AND json_extract(i, '$.regression.cv_error.kernel_ridge') < json_extract(i, '$.regression.cv_error.constant')
       AND json_extract(i, '$.pca.variance') BETWEEN 0.5 AND 1
  FROM (SELECT strength_info(r) AS i FROM models WHERE name = 'both');

SELECT json_extract(strength_info(r), '$.pca') IS NULL, json_extract(strength_info(r), '$.features'),
       json_extract(strength_info(r), '$.regression.method'), json_extract(strength_info(r), '$.levels[2].label')
  FROM models WHERE name = 'content';
-- expect: 1

SELECT json_extract(strength_info(r), '$.ranker.ordered_pairs') || ' ' || json_extract(strength_info(r), '$.ranker.similar_pairs')
  FROM models WHERE name = 'small';
-- expect: 6 2

-- ---- synthesis: strengths over the training range come out in that order ----
CREATE TABLE synth AS
SELECT t.value AS target, strength_synthesize(r, t.value) AS m FROM models, json_each('[-1,-0.5,0,0.5,1]') AS t
 WHERE name = 'knock';

SELECT 'synthesized motions rank in the order asked',
       count(*) = 5 AND sum(ok) = 5
  FROM (SELECT target, affect_strength((SELECT r FROM models WHERE name = 'knock'), m) >
                 coalesce(lag(affect_strength((SELECT r FROM models WHERE name = 'knock'), m)) OVER (ORDER BY target), -1e9) AS ok
          FROM synth) WHERE ok IS NOT NULL;
-- oom: skip

SELECT 'a synthesized motion is rigid and exports as BVH',
       motion_joints(m) = 26 AND motion_frames(m) > 20 AND length(motion_to_bvh(m)) > 1000
  FROM synth WHERE target = 0;
-- oom: skip

SELECT 'a label as the target: its mean strength',
       abs(affect_strength(r, strength_synthesize(r, '1.4')) - json_extract(strength_info(r), '$.levels[2].strength')) < 0.5
  FROM models WHERE name = 'knock';
-- oom: skip

-- ---- editing: a held-out mild motion to three strengths, in order ----
SELECT 'edited motions rank in the order asked',
       affect_strength(r, strength_edit(r, m, -1)) < affect_strength(r, strength_edit(r, m, 0))
       AND affect_strength(r, strength_edit(r, m, 0)) < affect_strength(r, strength_edit(r, m, 1))
  FROM models, s WHERE name = 'kf' AND seed = 5 AND action = 'knock' AND lvl = 0.2;
-- oom: skip

SELECT 'both feature blocks: edited motions rank in the order asked',
       affect_strength(r, strength_edit(r, m, -1)) < affect_strength(r, strength_edit(r, m, 0))
       AND affect_strength(r, strength_edit(r, m, 0)) < affect_strength(r, strength_edit(r, m, 1))
  FROM models, s WHERE name = 'blocks' AND seed = 5 AND action = 'knock' AND lvl = 0.2;
-- oom: skip

SELECT 'editing keeps the skeleton and roughly the duration',
       motion_joints(e) = motion_joints(m) AND motion_duration(e) BETWEEN motion_duration(m) / 3 AND motion_duration(m) * 3
  FROM (SELECT m, strength_edit(r, m, 0.5, '{"rigid":false}') AS e FROM models, s
         WHERE name = 'kf' AND seed = 6 AND action = 'wave' AND lvl = 0.8);
-- oom: skip

-- ---- the small model under fault injection ----
-- (without the rigid projection: its allocations are covered by skeleton.sql's motion_rigid;
-- with it, every one of ~1,700 injected failures re-ran the target search's projections, 4 min)
SELECT typeof(affect_strength(r, (SELECT m FROM s WHERE seed = 5 AND action = 'wave' AND lvl = 1.4))) FROM models WHERE name = 'small';
-- expect: real

SELECT motion_joints(strength_synthesize(r, 0.25, '{"rigid":false}')) FROM models WHERE name = 'small';
-- expect: 26

SELECT motion_joints(strength_edit(r, (SELECT m FROM s WHERE seed = 6 AND action = 'wave' AND lvl = 0.2), 1, '{"rigid":false}')) FROM models WHERE name = 'small';
-- expect: 26

SELECT json_extract(strength_info(r), '$.keyframes') FROM models WHERE name = 'small';
-- expect: 4

-- the Fisher representation (the default), the Laban vector and both blocks under fault
-- injection (their editing: the unit test's sweep, tests/core/test_strength.c)
SELECT typeof(affect_strength(r, (SELECT m FROM s WHERE seed = 5 AND action = 'wave' AND lvl = 1.4))) FROM models WHERE name = 'small_laban';
-- expect: real

SELECT typeof(affect_strength(r, (SELECT m FROM s WHERE seed = 5 AND action = 'wave' AND lvl = 0.8))) FROM models WHERE name = 'small_fisher';
-- expect: real

-- a Fisher model edits by the gradient of its ranker: the motion keeps its frames and joints,
-- stays rigid, and its strength moves to the level asked from either side
SELECT 'fisher edits toward the level asked', count(*) = 2
       AND sum(motion_frames(e) = motion_frames(m) AND motion_joints(e) = motion_joints(m)) = 2
       AND sum(abs(affect_strength(r, e) - lvl_s) < abs(affect_strength(r, m) - lvl_s)) = 2
       AND max(json_extract(motion_info(e), '$.bone_variation')) < 1e-4
  FROM (SELECT r, m, lvl_s, strength_edit(r, m, lvl_s) AS e
          FROM (SELECT r, m, json_extract(strength_info(r), '$.levels[' || CASE lvl WHEN 0.2 THEN 2 ELSE 0 END
                                                           || '].strength') AS lvl_s
                  FROM models, s
                 WHERE name = 'small_fisher' AND seed = 5 AND action = 'wave' AND lvl IN (0.2, 1.4)));
-- oom: skip

-- a level of the order without training motions is no class of the recognizer; the others rank
SELECT json_extract(i, '$.levels[1].motions') || ' ' || (json_extract(i, '$.levels[0].strength') < json_extract(i, '$.levels[2].strength'))
  FROM (SELECT strength_info(strength_train(m, CASE lvl WHEN 0.2 THEN 'mild' ELSE 'strong' END,
                                            '{"order":["mild","medium","strong"],"keyframes":4}')) AS i
          FROM s WHERE seed <= 2 AND lvl <> 0.8);
-- expect: 0 1

SELECT typeof(affect_strength(r, (SELECT m FROM s WHERE seed = 6 AND action = 'wave' AND lvl = 0.2))) FROM models WHERE name = 'small_both';
-- expect: real

SELECT strength_train(m, lvl, '{"pca_dims":2,"keyframes":3}') IS NOT NULL FROM s WHERE seed <= 1 AND action = 'knock';
-- expect: 1

-- ---- motion_keyframes ----
SELECT json_extract(motion_keyframes(m, 5), '$.keyframes') FROM s WHERE seed = 1 AND action = 'knock' AND lvl = 0.2;
-- expect: [0,49,84,98,122]

SELECT 'keyframes: the default 13, error falls with more keyframes, exact with every frame',
       json_array_length(motion_keyframes(m), '$.keyframes') = 13
       AND json_extract(motion_keyframes(m, 20), '$.rms_error') < json_extract(motion_keyframes(m, 5), '$.rms_error')
       AND json_extract(motion_keyframes(m, 4096), '$.rms_error') = 0
       AND json_array_length(motion_keyframes(m, 4096), '$.keyframes') = motion_frames(m)
  FROM s WHERE seed = 1 AND action = 'wave' AND lvl = 0.8;

SELECT motion_keyframes(NULL) IS NULL AND motion_keyframes(m, NULL) IS NULL FROM s LIMIT 1;
-- expect: 1

-- ---- rank_train / rank_score on float32 vectors (the sqlite-vec convention) ----
CREATE TABLE vec AS SELECT action, lvl, seed, laban_vector(m) AS v FROM s;

CREATE TABLE rankers AS
SELECT 'one' AS name, rank_train(v, lvl) AS r FROM vec WHERE seed <= 4
UNION ALL
SELECT 'clusters', rank_train(v, json_object('label', lvl, 'content', action), '{"clusters":2,"pairs":"same_content","seed":3}') FROM vec WHERE seed <= 4
UNION ALL
SELECT 'order', rank_train(v, CASE lvl WHEN 0.2 THEN 'calm' WHEN 1.4 THEN 'furious' END, '{"order":["calm","furious"],"similar":false,"C":10}') FROM vec WHERE seed <= 4;

SELECT 'ranker on Laban vectors: held-out accuracy ' || avg(a.sc > b.sc), avg(a.sc > b.sc) >= 0.8
  FROM (SELECT action, lvl, rank_score((SELECT r FROM rankers WHERE name = 'one'), v) AS sc FROM vec WHERE seed > 4) AS a
  JOIN (SELECT action, lvl, rank_score((SELECT r FROM rankers WHERE name = 'one'), v) AS sc FROM vec WHERE seed > 4) AS b
    ON a.action = b.action AND a.lvl > b.lvl;
-- oom: skip

SELECT 'pose clusters: held-out accuracy ' || avg(a.sc > b.sc), avg(a.sc > b.sc) >= 0.8
  FROM (SELECT action, lvl, rank_score((SELECT r FROM rankers WHERE name = 'clusters'), v) AS sc FROM vec WHERE seed > 4) AS a
  JOIN (SELECT action, lvl, rank_score((SELECT r FROM rankers WHERE name = 'clusters'), v) AS sc FROM vec WHERE seed > 4) AS b
    ON a.action = b.action AND a.lvl > b.lvl;
-- oom: skip

SELECT typeof(rank_score(r, (SELECT v FROM vec LIMIT 1))) FROM rankers WHERE name = 'order';
-- expect: real

SELECT rank_train(v, lvl, '{"clusters":2,"seed":1}') IS NOT NULL FROM vec WHERE seed <= 2;
-- expect: 1

SELECT rank_score(NULL, v) IS NULL, rank_score(r, NULL) IS NULL FROM vec, rankers LIMIT 1;
-- expect: 1

SELECT length(rank_train(v, lbl)) FROM (SELECT X'0000803F' AS v, 1 AS lbl UNION ALL SELECT X'00000040', 2);
-- expect: 96

-- ---- errors ----
SELECT strength_train(m, lvl, '{"keyframes":1}') FROM s;
-- error: strength_train: option "keyframes" must be from 2 to 4096, got 1

SELECT strength_train(m, lvl, '{"fraction":0}') FROM s;
-- error: strength_train: option "fraction" must be in (0, 1], got 0

SELECT strength_train(m, lvl, '{"order":["a"]}') FROM s;
-- error: strength_train: option "order" must be an array of 2 to 64 distinct non-empty labels

SELECT strength_train(m, lvl, '{"order":["a","a"]}') FROM s;
-- error: strength_train: option "order" must be an array of 2 to 64 distinct non-empty labels

SELECT strength_train(m, lvl, '{"clusters":2}') FROM s;
-- error: strength_train: unknown option "clusters" (expected order, pairs, label, content, fraction, similar, C, seed, progress, keyframes, pca_dims, regression, relative, standardize, features, descriptors)

SELECT strength_train(m, lvl, '{"features":"pose"}') FROM s;
-- error: strength_train: option "features" must be one of "keyframes", "laban", "both", "fisher", got "pose"

SELECT strength_train(m, lvl, '{"features":1}') FROM s;
-- error: strength_train: option "features" must be one of "keyframes", "laban", "both", "fisher", got number

SELECT strength_train(m, lvl, '{"descriptors":"pose"}') FROM s;
-- error: strength_train: option "descriptors" must be one of "none", "kinematics", "laban", "all", got "pose"

SELECT strength_train(m, lvl, '{"features":"laban","descriptors":"none"}') FROM s;
-- error: strength_train: option "descriptors" needs "features": "fisher"


SELECT strength_train(m, lvl, '{"regression":"mlp"}') FROM s;
-- error: strength_train: option "regression" must be one of "auto", "kernel_ridge", "local_linear", got "mlp"

SELECT strength_train(m, CASE WHEN seed = 1 THEN 'x' ELSE lvl END) FROM s;
-- error: strength_train: labels must be numbers when no "order" is given (got "x")

SELECT strength_train(m, 1) FROM s;
-- error: strength_train: the rows need at least 2 different labels (got 1)

SELECT strength_train(m, lvl, '{"pairs":"same_content"}') FROM s;
-- error: strength_train: row 1: "pairs": "same_content" needs labels as JSON objects with a "content"

SELECT strength_train(m, json_object('label', lvl), '{"pairs":"same_content"}') FROM s;
-- error: strength_train: row 1: "pairs": "same_content" needs the label's "content" (a string or a number)

SELECT strength_train(m, lvl, CASE WHEN seed = 3 THEN '{}' END) FROM s;
-- error: strength_train: options must be the same on every row

SELECT strength_train(m, X'00') FROM s;
-- error: strength_train: argument 2 (the label) must be text or a number, got blob

SELECT strength_train(motion_slice(m, 0, 5), lvl) FROM s;
-- error: strength_train: row 1: the motion has 6 frames, fewer than the 13 keyframes

SELECT strength_train(m, lvl) FROM (SELECT * FROM (SELECT m, lvl FROM s LIMIT 2) UNION ALL SELECT * FROM (SELECT motion_select(m, '["Hips","Spine"]'), lvl FROM s LIMIT 3));
-- error: strength_train: row 3: the motion's joints differ from the first motion's (2 joints, the first has 26)

SELECT length(strength_train(m, lvl, '{"order":["0.2","1.4"],"pca_dims":4}')) > 1000 FROM s WHERE seed <= 2 AND action = 'knock';
-- expect: 1

SELECT strength_train(m, lvl, '{"order":["mild","strong"]}') FROM s;
-- error: strength_train: need at least 2 motions with a label of the order (got 0)

SELECT affect_strength('x', m) FROM s LIMIT 1;
-- error: affect_strength: argument 1 must be a strength model BLOB (from strength_train), got text

SELECT affect_strength(X'41465354', m) FROM s LIMIT 1;
-- error: affect_strength: argument 1 is not a valid strength model: not a strength model BLOB (4 bytes, the header alone is 180)

SELECT affect_strength(r, motion_select(m, '["Hips","Spine"]')) FROM models, s WHERE name = 'small' LIMIT 1;
-- error: affect_strength: 2 joints, the model has 26

SELECT affect_strength(r, motion_slice(m, 0, 2)) FROM models, s WHERE name = 'small' LIMIT 1;
-- error: affect_strength: 3 frames, fewer than the 4 keyframes

SELECT affect_strength((SELECT r FROM rankers LIMIT 1), m) FROM s LIMIT 1;
-- error: affect_strength: argument 1 is not a valid strength model: not a strength model (bad magic bytes at offset 0)

SELECT strength_synthesize(r, 'furious') FROM models WHERE name = 'small';
-- error: strength_synthesize: argument 2: "furious" is not a trained label of the model

SELECT strength_synthesize(r, 0, '{"rigid":1}') FROM models WHERE name = 'small';
-- error: strength_synthesize: option "rigid" must be true or false, got number

SELECT strength_synthesize(r, 0) FROM models WHERE name = 'small_laban';
-- error: strength_synthesize: the model ranks by the Laban vector alone, which synthesized and edited motions do not follow: train it with "features": "keyframes" (or "both") to synthesize or edit

SELECT strength_edit(r, m, 0) FROM models, s WHERE name = 'small_laban' LIMIT 1;
-- error: strength_edit: the model ranks by the Laban vector alone, which synthesized and edited motions do not follow: train it with "features": "keyframes" (or "both") to synthesize or edit

SELECT strength_synthesize(r, 0) FROM models WHERE name = 'small_fisher';
-- error: strength_synthesize: the model ranks by the recognizer's Fisher representation, which edits a motion but has none to synthesize from: train it with "features": "keyframes" (or "both") to synthesize

SELECT affect_strength(r, motion_select(m, '["Hips","Spine"]')) FROM models, s WHERE name = 'small_laban' LIMIT 1;
-- error: affect_strength: 2 joints, the model has 26

SELECT strength_edit(r, 'm', 0) FROM models WHERE name = 'small';
-- error: strength_edit: argument 2 must be a motion BLOB, got text

SELECT motion_keyframes(m, 1) FROM s LIMIT 1;
-- error: motion_keyframes: argument 2 (keyframes) must be from 2 to 4096, got 1

SELECT rank_train(v, lvl) FROM (SELECT X'0000803F' AS v, 1 AS lvl UNION ALL SELECT X'0000803F00000040', 2);
-- error: rank_train: row 2: the vector has 2 dimensions, the first 1

SELECT rank_train(v, lvl) FROM (SELECT X'00008000FF' AS v, 1 AS lvl);
-- error: rank_train: argument 1 must be a float32 vector BLOB (4 bytes per value), got 5 bytes

SELECT rank_train(v, lvl) FROM (SELECT X'0000C07F' AS v, 1 AS lvl);
-- error: rank_train: row 1: value 0 of the vector is not finite

SELECT rank_train(v, lvl, '{"clusters":5}') FROM (SELECT X'0000803F' AS v, 1 AS lvl UNION ALL SELECT X'00000040', 2);
-- error: rank_train: clusters (5) exceeds the number of samples (2)

SELECT rank_train(v, lvl, '{"clusters":0}') FROM vec;
-- error: rank_train: option "clusters" must be from 1 to 256, got 0

SELECT rank_score(r, X'0000803F') FROM rankers WHERE name = 'one';
-- error: rank_score: the vector has 1 dimensions, the ranker 27

SELECT rank_score(X'00', X'0000803F');
-- error: rank_score: argument 1 is not a valid ranker: not a ranker BLOB (1 bytes, the header alone is 80)
