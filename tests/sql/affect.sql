-- affect.sql — SQL-level specification of the emotion recognizer (SCIENCE.md §3; thesis
-- chapter 4): affect_train, affect_classify, affect_scores, fisher_score, affect_embed,
-- affect_info, and the table-valued affect_salience and affect_crossval.
-- Run by tests/sql/test_sql.c; see its header for the annotations. The classifiers and the
-- cross-validation tables are made once by CREATE TABLE … AS (statements that write run once,
-- also in the --oom mode); the checks over many motions of the big classifier, and those in
-- plain SQL over stored results, are "-- oom: skip"; a small classifier (angry and sad waves,
-- the right hand, 2 states, 20 frames) covers every function under fault injection.
-- fisher_score and affect_embed return float32 vectors, decoded here in SQL (the f32 view).

CREATE TABLE s(action TEXT, emotion TEXT, seed INTEGER, m BLOB);
INSERT INTO s
SELECT a.value, e.value, k.value, motion_synth(a.value, e.value, k.value)
  FROM json_each('["knock","wave","bow"]') AS a,
       json_each('["neutral","happy","sad","angry"]') AS e,
       json_each('[1,2,3,4,5,6]') AS k;

-- float32 vectors (fisher_score, affect_embed) decoded in SQL: a byte table, then
-- value = ±(1 + mantissa / 2^23) · 2^(exponent − 127)
CREATE TABLE hexbyte(h TEXT PRIMARY KEY, v INTEGER);
WITH RECURSIVE n(i) AS (SELECT 0 UNION ALL SELECT i + 1 FROM n WHERE i < 255)
INSERT INTO hexbyte SELECT printf('%02X', i), i FROM n;

-- ---- registration ----
SELECT group_concat(name || '/' || narg || '/' || type, ' ') FROM (
  SELECT DISTINCT name, narg, type FROM pragma_function_list
   WHERE (name LIKE 'affect\_%' ESCAPE '\' OR name LIKE 'fisher\_%' ESCAPE '\')
     AND name NOT IN ('affect_version', 'affect_build_info', 'affect_generate', 'affect_generate_explain', 'affect_strength', 'affect_heatmap') ORDER BY name, narg);
-- expect: affect_classify/2/s affect_classify/3/s affect_crossval_json/4/a affect_embed/2/s affect_info/1/s affect_scores/2/s affect_train/2/a affect_train/3/a fisher_score/2/s

SELECT 'the recognizer functions are deterministic and innocuous', count(*) = 9
  FROM pragma_function_list
 WHERE name IN ('affect_train', 'affect_classify', 'affect_scores', 'fisher_score', 'affect_embed',
                'affect_info', 'affect_crossval_json')
   AND (flags & 0x000000800) <> 0 AND (flags & 0x000200000) <> 0;

SELECT group_concat(name, ' ') FROM (
  SELECT name FROM pragma_module_list WHERE name LIKE 'affect\_%' ESCAPE '\' ORDER BY name);
-- expect: affect_crossval affect_salience

-- ---- the small classifier and its probes (frames 30 .. 49 of the angry and sad waves) ----
CREATE TABLE probe AS
SELECT seed, emotion, motion_slice(m, 30, 49) AS m FROM s
 WHERE action = 'wave' AND emotion IN ('sad', 'angry') ORDER BY seed, emotion;
CREATE TABLE small AS
SELECT affect_train(m, emotion, '{"states":2,"mixtures":1,"joints":["right_hand"],"max_iter":2,"svm_c":1,"spca_dims":1,"knn_k":1,"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false}') AS model
  FROM probe WHERE seed <= 3;

SELECT 'the small classifier: an AFCL BLOB of version 2', substr(model, 1, 8) = x'4146434C02000000'
   AND length(model) BETWEEN 2000 AND 4000
  FROM small;

-- ---- the big classifier: 4 emotions, performers 1–4, three actions each ----
CREATE TABLE c AS
SELECT affect_train(m, emotion, '{"states":5,"mixtures":1,"joints":["right_hand","left_hand","head","chest"],"velocity":true,"max_iter":8,"covariance":"full","frame":"first","descriptors":"none","mirror":false}') AS model
  FROM s WHERE seed <= 4;

-- ---- the defaults: the measured best (docs/EVALUATION.md, "Choosing the defaults") ----
CREATE TABLE d AS SELECT affect_train(m, emotion) AS model FROM s WHERE seed <= 4;

WITH t AS MATERIALIZED (SELECT affect_info(model) AS i FROM d)
SELECT 'defaults: the body frame, 5 states × 1 diagonal, every motion and its mirror image, kinematic summaries at weight 0.1',
       json_extract(i, '$.features.frame') = 'body' AND json_extract(i, '$.features.velocity') = 0
   AND json_extract(i, '$.features.root') = 0 AND json_extract(i, '$.hmm.states') = 5
   AND json_extract(i, '$.hmm.mixtures') = 1 AND json_extract(i, '$.hmm.covariance') = 'diag'
   AND json_extract(i, '$.hmm.max_iter') = 20 AND json_extract(i, '$.mirror') = 1
   AND json_extract(i, '$.training_motions') = 96
   AND json_extract(i, '$.descriptors') = 'kinematics'
   AND json_extract(i, '$.descriptor_weight') = 0.1
   AND json_extract(i, '$.dimensions.descriptors') = 21
  FROM t;

SELECT 'defaults: held-out performers 5 and 6 by SVM ' || svm, svm >= 0.9
  FROM (SELECT avg(emotion = affect_classify(model, m)) AS svm FROM s, d WHERE seed >= 5);
-- oom: skip

SELECT affect_train(m, emotion, '{"joints":["right_hand"],"mirror":true}') FROM probe;
-- error: affect_train: joint "Hand_R" has no mirror partner ("Hand_L" is not among the observed joints)

SELECT json_extract(affect_info(affect_train(m, emotion, '{"states":2,"joints":["right_hand"]}')), '$.mirror') FROM probe;
-- expect: 0

SELECT affect_train(m, emotion, '{"mirror":"yes"}') FROM probe;
-- error: affect_train: option "mirror" must be true, false or "auto"

SELECT affect_train(m, emotion, '{"descriptors":"speed"}') FROM probe;
-- error: affect_train: option "descriptors" must be one of "none", "kinematics", "laban", "all", got "speed"

SELECT affect_train(m, emotion, '{"root":true,"frame":"first"}') FROM probe;
-- error: affect_train: row 1: root velocity and turning rate need the body frame

-- ---- the storage of the long vectors (docs/FORMATS.md, "the compact storage") ----
SELECT 'storage compact: version 3, smaller, the same labels as the float32 storage',
       substr(q.model, 1, 8) = x'4146434C03000000' AND length(q.model) < length(f.model)
   AND substr(f.model, 1, 8) = x'4146434C02000000' AND f.model = small.model
   AND json_extract(affect_info(q.model), '$.format') = 3
   AND (SELECT count(*) FROM probe
         WHERE affect_classify(q.model, m) = affect_classify(f.model, m)
           AND affect_classify(q.model, m, 'knn') = affect_classify(f.model, m, 'knn')) = 12
  FROM small,
       (SELECT affect_train(m, emotion, '{"states":2,"mixtures":1,"joints":["right_hand"],"max_iter":2,"svm_c":1,"spca_dims":1,"knn_k":1,"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"storage":"compact"}') AS model
          FROM probe WHERE seed <= 3) AS q,
       (SELECT affect_train(m, emotion, '{"states":2,"mixtures":1,"joints":["right_hand"],"max_iter":2,"svm_c":1,"spca_dims":1,"knn_k":1,"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"storage":"float32"}') AS model
          FROM probe WHERE seed <= 3) AS f;

SELECT affect_train(m, emotion, '{"storage":"float16"}') FROM probe;
-- error: affect_train: option "storage" must be one of "auto", "float32", "compact", got "float16"

-- ---- recognition of the unseen performers 5 and 6 ----
SELECT 'held-out performers 5 and 6: svm ' || svm || ', knn ' || knn || ', ml ' || ml,
       svm >= 0.95 AND knn >= 0.95 AND ml >= 0.95 AND n = 24
  FROM (SELECT avg(emotion = affect_classify(model, m)) AS svm,
               avg(emotion = affect_classify(model, m, 'knn')) AS knn,
               avg(emotion = affect_classify(model, m, 'ml')) AS ml, count(*) AS n
          FROM s, c WHERE seed >= 5);
-- oom: skip

SELECT emotion, affect_classify(model, m, 'svm') = emotion FROM s, c
 WHERE seed = 6 AND action = 'bow';
-- oom: skip

-- one row per held-out motion: the scores, the embedding and the Fisher vector
CREATE TABLE held AS
SELECT s.rowid AS id, emotion, affect_classify(model, m) AS svm, affect_classify(model, m, 'knn') AS knn,
       affect_classify(model, m, 'ml') AS ml, affect_classify(model, m, NULL) AS dflt,
       affect_scores(model, m) AS j, affect_embed(model, m) AS e, fisher_score(model, m) AS f
  FROM s, c WHERE seed >= 5;

SELECT 'affect_classify: the default method is svm', count(*) = 24 AND sum(dflt = svm) = 24 FROM held;
-- oom: skip

SELECT 'affect_scores: valid JSON whose labels are those of affect_classify', count(*) = 24
   AND sum(json_valid(j)) = 24
   AND sum(json_extract(j, '$.label.svm') = svm AND json_extract(j, '$.label.knn') = knn
           AND json_extract(j, '$.label.ml') = ml) = 24
  FROM held;
-- oom: skip

SELECT 'affect_scores: the ML label has the largest log-likelihood (motion ' || id || ')',
       json_extract(j, '$.classes.' || ml || '.loglik') =
       (SELECT max(json_extract(value, '$.loglik')) FROM json_each(j, '$.classes'))
  FROM held;
-- oom: skip

SELECT 'affect_scores: 6 SVM votes (one per pair), the decision values antisymmetric (motion ' || id || ')',
       (SELECT sum(json_extract(value, '$.svm_votes')) FROM json_each(j, '$.classes')) = 6
   AND NOT EXISTS (SELECT 1 FROM json_each(j, '$.classes') AS a, json_each(a.value, '$.decision') AS d
                    WHERE d.value <> -json_extract(j, '$.classes.' || d.key || '.decision.' || a.key))
   AND NOT EXISTS (SELECT 1 FROM json_each(j, '$.classes') AS a
                    WHERE json_extract(a.value, '$.svm_votes') <>
                          (SELECT count(*) FROM json_each(a.value, '$.decision') WHERE value > 0))
   AND json_extract(j, '$.classes.' || svm || '.svm_votes') =
       (SELECT max(json_extract(value, '$.svm_votes')) FROM json_each(j, '$.classes'))
  FROM held;
-- oom: skip

SELECT 'affect_scores: 5 kNN votes, the most for the kNN label; a 3-D embedding (motion ' || id || ')',
       (SELECT sum(json_extract(value, '$.knn_votes')) FROM json_each(j, '$.classes')) = 5
   AND json_extract(j, '$.classes.' || knn || '.knn_votes') =
       (SELECT max(json_extract(value, '$.knn_votes')) FROM json_each(j, '$.classes'))
   AND json_array_length(j, '$.embedding') = 3
  FROM held;
-- oom: skip

CREATE VIEW f32 AS
SELECT o.id AS id, o.i AS i,
       CASE WHEN (u >> 23) & 255 = 0 THEN 0.0
            ELSE (CASE WHEN u >> 31 THEN -1 ELSE 1 END) * (1 + (u & 8388607) / 8388608.0) *
                 CASE WHEN ((u >> 23) & 255) >= 127 THEN (1 << (((u >> 23) & 255) - 127))
                      ELSE 1.0 / (1 << (127 - ((u >> 23) & 255))) END END AS v
  FROM (SELECT b.id, b.i, b0.v | (b1.v << 8) | (b2.v << 16) | (b3.v << 24) AS u
          FROM (SELECT id, i, hex(substr(x, 4 * i + 1, 4)) AS h FROM vec) AS b,
               hexbyte AS b0, hexbyte AS b1, hexbyte AS b2, hexbyte AS b3
         WHERE b0.h = substr(b.h, 1, 2) AND b1.h = substr(b.h, 3, 2) AND b2.h = substr(b.h, 5, 2)
           AND b3.h = substr(b.h, 7, 2)) AS o;

CREATE TABLE vec(id INTEGER, i INTEGER, x BLOB);
INSERT INTO vec SELECT held.id, k.value, e FROM held, json_each('[0,1,2]') AS k;

SELECT 'affect_embed: the embedding of affect_scores as float32', count(*) = 72
   AND max(abs(v - json_extract(j, '$.embedding[' || i || ']')) /
           (abs(json_extract(j, '$.embedding[' || i || ']')) + 1e-30)) < 1e-6
  FROM f32 JOIN held USING (id);
-- oom: skip

SELECT 'fisher_score and affect_embed: float32 vectors of 6600 and 3 values', count(*) = 24
   AND min(length(f)) = 4 * 6600 AND max(length(f)) = 4 * 6600 AND min(length(e)) = 12
   AND max(length(e)) = 12
  FROM held;
-- oom: skip

DELETE FROM vec;
WITH RECURSIVE n(i) AS (SELECT 0 UNION ALL SELECT i + 1 FROM n WHERE i < 6599)
INSERT INTO vec SELECT id, i, f FROM held, n WHERE id IN (SELECT min(id) FROM held UNION SELECT max(id) FROM held);

SELECT 'fisher_score: z-scores limited to ±5 (score_clip), and the limit is reached',
       count(*) = 2 * 6600 AND max(abs(v)) = 5.0 AND sum(abs(v) = 5.0) > 0
  FROM f32;
-- oom: skip

-- ---- determinism ----
SELECT 'training twice gives identical BLOBs',
       (SELECT affect_train(m, emotion, '{"states":5,"mixtures":1,"joints":["right_hand","left_hand","head","chest"],"velocity":true,"max_iter":8,"covariance":"full","frame":"first","descriptors":"none","mirror":false}')
          FROM s WHERE seed <= 4) = model
  FROM c;
-- oom: skip

SELECT 'training on 3 threads (class HMMs and Fisher scores in parallel) gives the same BLOB',
       (SELECT affect_train(m, emotion, '{"threads":3}') FROM s WHERE seed <= 4) = model
  FROM d;
-- oom: skip

SELECT affect_train(m, emotion, '{"threads":65}') FROM probe;
-- error: affect_train: option "threads" must be from 1 to 64, got 65

-- a refused allocation of 16 MiB or more is an error naming it, not a bare SQLITE_NOMEM (issue
-- 14): 96 rows (48 motions and their mirror images) of 25,284 Fisher scores, with 22 MiB left
SELECT affect_train(m, emotion, '{"states":2,"mixtures":4,"covariance":"full","mirror":true,"max_iter":1,"descriptors":"none","svm_c":1}')
  FROM s WHERE seed <= 4;
-- error: affect_train: cannot allocate the 96 x 25284 block of Fisher scores (18.5 MiB): out of memory
-- heap-limit: 23068672
-- oom: skip

SELECT 'the small classifier too, and the class order does not depend on the row order',
       (SELECT affect_train(m, emotion, '{"states":2,"mixtures":1,"joints":["right_hand"],"max_iter":2,"svm_c":1,"spca_dims":1,"knn_k":1,"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false}')
          FROM probe WHERE seed <= 3) = model
   AND (SELECT json_extract(affect_info(affect_train(m, emotion, '{"states":2,"mixtures":1,"joints":["right_hand"],"max_iter":1,"svm_c":1,"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false}')), '$.classes')
          FROM (SELECT * FROM probe WHERE seed <= 2 ORDER BY emotion DESC)) = '["angry","sad"]'
  FROM small;
-- oom: skip

-- ---- affect_info ----
WITH t AS MATERIALIZED (SELECT affect_info(model) AS i FROM c)
SELECT 'affect_info: classes, training set, dimensions, HMM configuration, features',
       json_valid(i) AND json_extract(i, '$.format') = 2
   AND json_extract(i, '$.classes') = '["angry","happy","neutral","sad"]'
   AND json_extract(i, '$.training_motions') = 48
   AND json_extract(i, '$.per_class') = '{"angry":12,"happy":12,"neutral":12,"sad":12}'
   AND json_extract(i, '$.dimensions') = '{"observation":24,"per_hmm":1650,"fisher":6600,"descriptors":0,"representation":6600,"spca":3}'
   AND json_extract(i, '$.hmm') = json('{"states":5,"mixtures":1,"dim":24,"covariance":"full","topology":"ergodic","max_jump":0,"start":"first","max_iter":8,"tol":0.0001,"reg":0.0001,"seed":1}')
   AND json_extract(i, '$.features') = json('{"joints":["right_hand","left_hand","head","chest"],"skeleton":["Hand_R","Hand_L","Head","Chest"],"parents":[3,3,3,-1],"frame":"first","normalize":true,"scale":"arm","up":"y","velocity":true,"root":false,"fps":30,"unit":"arm","dim":24}')
  FROM t;

WITH t AS MATERIALIZED (SELECT affect_info(model) AS i FROM c)
SELECT 'affect_info: the defaults (all groups, z-scores clipped at 5, C by cross-validation, rbf sPCA, 5-NN) and the training report',
       json_extract(i, '$.groups') = '["start","transitions","weights","means","covariances"]'
   AND json_extract(i, '$.score_normalization') = 'zscore' AND json_extract(i, '$.score_clip') = 5
   AND json_extract(i, '$.svm.C') IN (0.001, 0.01, 0.1, 1, 10, 100, 1000)
   AND json_extract(i, '$.svm.C_chosen_by') = 'cross-validation'
   AND json_extract(i, '$.svm.cv_accuracy') BETWEEN 0.9 AND 1
   AND json_extract(i, '$.svm.support_vectors') BETWEEN 4 AND 48
   AND json_extract(i, '$.spca.kernel') = 'rbf' AND json_extract(i, '$.spca.sigma') = 0.25
   AND json_extract(i, '$.spca.dims') = 3 AND json_array_length(i, '$.spca.eigenvalues') = 3
   AND json_extract(i, '$.spca.eigenvalues[0]') >= json_extract(i, '$.spca.eigenvalues[1]')
   AND json_extract(i, '$.spca.eigenvalues[1]') >= json_extract(i, '$.spca.eigenvalues[2]')
   AND json_extract(i, '$.spca.eigenvalues[2]') > 0
   AND json_extract(i, '$.knn_k') = 5
   AND json_extract(i, '$.training_accuracy.ml') >= 0.95
   AND json_extract(i, '$.training_accuracy.svm') >= 0.95
   AND json_extract(i, '$.training_accuracy.knn_leave_one_out') >= 0.9
  FROM t;

WITH t AS MATERIALIZED (SELECT affect_info(model) AS i FROM small)
SELECT 'affect_info of the small classifier: the options given',
       json_extract(i, '$.classes') = '["angry","sad"]' AND json_extract(i, '$.training_motions') = 6
   AND json_extract(i, '$.dimensions') = '{"observation":3,"per_hmm":24,"fisher":48,"descriptors":0,"representation":48,"spca":1}'
   AND json_extract(i, '$.svm.C') = 1 AND json_extract(i, '$.svm.C_chosen_by') = 'option'
   AND json_type(i, '$.svm.cv_accuracy') = 'null' AND json_extract(i, '$.knn_k') = 1
   AND json_extract(i, '$.features.joints') = '["right_hand"]'
  FROM t;

SELECT 'JSON results nest as objects', json_type(json_object('i', affect_info(model)), '$.i') = 'object'
   AND json_type(json_object('s', affect_scores(model, m)), '$.s') = 'object'
  FROM small, probe WHERE seed = 5 AND emotion = 'sad';

-- options: groups, no normalization, no limit, a linear sPCA, the sPCA dims capped at C − 1
CREATE TABLE variants AS
SELECT 'a' AS name, affect_train(m, emotion, '{"states":2,"mixtures":1,"joints":["right_hand"],"max_iter":2,"svm_c":0.5,"groups":["transitions","means"],"score_normalization":"none","score_clip":0,"spca_kernel":"linear","spca_dims":4,"knn_k":3,"svm_folds":3,"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false}') AS model
  FROM probe WHERE seed <= 3
UNION ALL
SELECT 'b', affect_train(m, emotion, '{"states":2,"mixtures":1,"joints":["right_hand"],"max_iter":2,"groups":"all","svm_c":"auto","svm_folds":3,"spca_sigma":2,"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false}')
  FROM probe WHERE seed <= 3;

WITH t AS MATERIALIZED (SELECT affect_info(model) AS i FROM variants WHERE name = 'a')
SELECT 'affect_info reports the options', json_extract(i, '$.groups') = '["transitions","means"]'
   AND json_extract(i, '$.score_normalization') = 'none' AND json_extract(i, '$.score_clip') = 0
   AND json_extract(i, '$.svm.C') = 0.5 AND json_extract(i, '$.spca.kernel') = 'linear'
   AND json_extract(i, '$.spca.sigma') = 0 AND json_extract(i, '$.spca.dims') = 1
   AND json_extract(i, '$.dimensions.per_hmm') = 2 * 2 + 2 * 3 AND json_extract(i, '$.knn_k') = 3
  FROM t;

WITH t AS MATERIALIZED (SELECT affect_info(model) AS i FROM variants WHERE name = 'b')
SELECT 'svm_c "auto" chooses C by cross-validation', json_extract(i, '$.svm.C_chosen_by') = 'cross-validation'
   AND json_extract(i, '$.svm.cv_accuracy') BETWEEN 0 AND 1 AND json_extract(i, '$.spca.sigma') = 2
   AND json_extract(i, '$.groups') = '["start","transitions","weights","means","covariances"]'
  FROM t;

-- the Fisher vectors of a held-out sad wave: without z-scores the raw score, not limited
DELETE FROM vec;
WITH RECURSIVE n(i) AS (SELECT 0 UNION ALL SELECT i + 1 FROM n WHERE i < 19)
INSERT INTO vec SELECT 1, i, f FROM n, (SELECT fisher_score(v.model, p.m) AS f FROM variants AS v, probe AS p
                                         WHERE v.name = 'a' AND p.seed = 5 AND p.emotion = 'sad');
WITH RECURSIVE n(i) AS (SELECT 0 UNION ALL SELECT i + 1 FROM n WHERE i < 47)
INSERT INTO vec SELECT 2, i, f FROM n, (SELECT fisher_score(c.model, p.m) AS f FROM small AS c, probe AS p
                                         WHERE p.seed = 5 AND p.emotion = 'sad');

SELECT 'without z-scores the Fisher vector is the raw score, not limited to ±5',
       count(*) = 20 AND max(abs(v)) > 5 FROM f32 WHERE id = 1;

SELECT 'with z-scores (the small classifier) it is', count(*) = 48 AND max(abs(v)) <= 5
  FROM f32 WHERE id = 2;

-- numbers as labels: compared as text, classes in byte order
CREATE TABLE numeric AS
SELECT affect_train(m, CASE emotion WHEN 'sad' THEN 10 ELSE 9 END, '{"states":2,"mixtures":1,"joints":["right_hand"],"max_iter":1,"svm_c":1}') AS model
  FROM probe WHERE seed <= 2;

SELECT 'numeric labels become text classes', json_extract(affect_info(model), '$.classes') = '["10","9"]'
   AND affect_classify(numeric.model, probe.m, 'ml') = '10'
  FROM numeric, probe WHERE seed = 1 AND emotion = 'sad';

-- ---- the grid search ----
CREATE TABLE cvs AS SELECT action, emotion, seed, m FROM s WHERE action IN ('knock', 'wave') AND seed <= 4;
CREATE TABLE gridc AS
SELECT affect_train(m, emotion, '{"states":3,"mixtures":1,"joints":["right_hand","head"],"velocity":true,"max_iter":4,"svm_c":1,"grid":{"spca_dims":[1,2,3],"spca_sigma":[0.5,1],"knn_k":[1,3],"folds":4},"covariance":"full","frame":"first","descriptors":"none","mirror":false}') AS model
  FROM cvs;

WITH t AS MATERIALIZED (SELECT affect_info(model) AS i FROM gridc)
SELECT 'the grid chooses spca_dims, spca_sigma and knn_k from its lists',
       json_extract(i, '$.spca.dims') IN (1, 2, 3) AND json_extract(i, '$.spca.sigma') IN (0.5, 1)
   AND json_extract(i, '$.knn_k') IN (1, 3) AND json_extract(i, '$.dimensions.spca') = json_extract(i, '$.spca.dims')
  FROM t;

-- ---- affect_salience ----
SELECT 'affect_salience: classes × states × mixtures rows, weights ≥ 0, top lists heaviest first',
       count(*) = 4 * 5 * 1 AND min(weight) >= 0
   AND sum(json_valid(top)) = 20 AND sum(json_array_length(top) = 5) = 20
   AND sum(weight = json_extract(top, '$[0].weight')) = 20
   AND NOT EXISTS (SELECT 1 FROM affect_salience((SELECT model FROM c)) AS a, json_each(a.top) AS x
                    WHERE x.key > 0 AND json_extract(x.value, '$.weight') > json_extract(a.top, '$[' || (x.key - 1) || '].weight'))
   AND group_concat(DISTINCT label) = 'angry,happy,neutral,sad'
  FROM affect_salience((SELECT model FROM c));
-- oom: skip

SELECT 'affect_salience: coordinates name the joints (v. for velocities); postures are 1-frame motions on the training skeleton',
       count(*) = 4 AND sum(label IN ('angry', 'sad')) = 4 AND max(state) = 1 AND max(mixture) = 0
   AND sum(json_array_length(top) = 2) = 4
   AND sum(json_extract(top, '$[0].coordinates[0]') GLOB 'right_hand.[xyz]') = 4
   AND sum(motion_frames(posture) = 1 AND motion_joints(posture) = 1) = 4
   AND sum(json_extract(motion_info(posture), '$.names') = '["Hand_R"]') = 4
  FROM affect_salience((SELECT model FROM small), 2);

SELECT 'affect_salience: velocity coordinates', count(*) > 0
  FROM affect_salience((SELECT model FROM c), 32) AS a, json_each(a.top) AS x
 WHERE json_extract(x.value, '$.coordinates[1]') GLOB 'v.*';
-- oom: skip

SELECT count(*) FROM affect_salience(NULL);
-- expect: 0

SELECT count(*) FROM affect_salience((SELECT model FROM small), NULL);
-- expect: 4

CREATE VIEW salience_view AS SELECT * FROM affect_salience((SELECT model FROM small));
SELECT 'affect_salience is innocuous: usable in a view', count(*) = 4 FROM salience_view;

SELECT * FROM affect_salience((SELECT model FROM variants WHERE name = 'a'));
-- error: affect_salience: the classifier has no covariance scores (trained without the covariances group)

SELECT * FROM affect_salience((SELECT model FROM small), 0);
-- error: affect_salience: argument 2 (top) must be an integer from 1 to 32, got 0

SELECT * FROM affect_salience((SELECT model FROM small), 33);
-- error: affect_salience: argument 2 (top) must be an integer from 1 to 32, got 33

SELECT * FROM affect_salience((SELECT model FROM small), '3');
-- error: affect_salience: argument 2 (top) must be an integer from 1 to 32, got text

SELECT * FROM affect_salience('x');
-- error: affect_salience: argument 1 must be a classifier BLOB (from affect_train), got text

SELECT * FROM affect_salience(x'4146434C');
-- error: affect_salience: argument 1 is not a valid classifier: truncated: 4 bytes is shorter than the classifier header

SELECT * FROM affect_salience();
-- error: affect_salience: argument 1 is required, as in SELECT * FROM affect_salience(:classifier [, top])

-- ---- affect_crossval: stratified k-fold ----
CREATE TABLE cv AS SELECT * FROM affect_crossval('cvs', 'm', 'emotion', '{"states":2,"mixtures":1,"joints":["head"],"max_iter":2,"svm_c":0.01,"folds":4,"seed":3,"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false}');
CREATE TABLE cv_again AS SELECT * FROM affect_crossval('cvs', 'm', 'emotion', '{"states":2,"mixtures":1,"joints":["head"],"max_iter":2,"svm_c":0.01,"folds":4,"seed":3,"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false}');
CREATE TABLE cv_seed4 AS SELECT * FROM affect_crossval('cvs', 'm', 'emotion', '{"states":2,"mixtures":1,"joints":["head"],"max_iter":2,"svm_c":0.01,"folds":4,"seed":4,"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false}');
CREATE TABLE cv_threads AS SELECT * FROM affect_crossval('cvs', 'm', 'emotion', '{"states":2,"mixtures":1,"joints":["head"],"max_iter":2,"svm_c":0.01,"folds":4,"seed":3,"threads":2,"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false}');

SELECT 'affect_crossval: 3 methods × (4 folds + a summary)', count(*) = 15
   AND sum(fold IS NULL) = 3 AND group_concat(DISTINCT method) = 'ml,svm,knn'
  FROM cv;

SELECT 'the same seed gives the same rows, another seed other folds',
       (SELECT count(*) FROM (SELECT * FROM cv EXCEPT SELECT * FROM cv_again)) = 0
   AND (SELECT count(*) FROM cv_again) = 15
   AND (SELECT count(*) FROM (SELECT * FROM cv EXCEPT SELECT * FROM cv_seed4)) > 0;

SELECT 'two threads give the same rows as one',
       (SELECT count(*) FROM (SELECT * FROM cv EXCEPT SELECT * FROM cv_threads)) = 0
   AND (SELECT count(*) FROM cv_threads) = 15;

SELECT * FROM affect_crossval('cvs', 'm', 'emotion', '{"threads":0,"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"states":7,"mixtures":4,"max_iter":50}');
-- error: affect_crossval: affect_crossval_json: option "threads" must be from 1 to 64, got 0

SELECT 'fold rows: 8 held out (2 per emotion), 24 training; accuracy from the confusion matrix: ' || method || ' ' || fold,
       n_test = 8 AND n_train = 24 AND held_out IS NULL AND fold BETWEEN 1 AND 4
   AND json_valid(confusion) AND json_extract(confusion, '$.labels') = '["angry","happy","neutral","sad"]'
   AND (SELECT count(*) FROM json_each(confusion, '$.matrix') AS r
         WHERE (SELECT sum(value) FROM json_each(r.value)) = 2) = 4
   AND abs(accuracy - (SELECT sum(json_extract(confusion, '$.matrix[' || k || '][' || k || ']'))
                         FROM (SELECT value AS k FROM json_each('[0,1,2,3]'))) / 8.0) < 1e-12
   AND balanced_accuracy BETWEEN 0 AND 1 AND macro_f1 BETWEEN 0 AND 1
   AND accuracy_sd IS NULL AND balanced_accuracy_sd IS NULL AND macro_f1_sd IS NULL
   AND pooled_accuracy IS NULL
  FROM cv WHERE fold IS NOT NULL;

SELECT 'fold rows: what the classifier used (params): ' || method || ' ' || fold,
       CASE method WHEN 'ml' THEN params IS NULL
                   WHEN 'svm' THEN json_valid(params) AND params = '{"svm_c":0.01}'
                   ELSE json_valid(params) AND params = '{"spca_dims":3,"spca_sigma":0.25,"knn_k":5}' END
  FROM cv WHERE fold IS NOT NULL;

SELECT 'summary rows: the means and sample standard deviations of the folds: ' || sm.method,
       sm.held_out IS NULL AND sm.n_train IS NULL AND sm.n_test = 32 AND sm.params IS NULL
   AND abs(sm.accuracy - avg(f.accuracy)) < 1e-12
   AND abs(sm.balanced_accuracy - avg(f.balanced_accuracy)) < 1e-12
   AND abs(sm.macro_f1 - avg(f.macro_f1)) < 1e-12
   AND abs(sm.accuracy_sd * sm.accuracy_sd * 3 - sum((f.accuracy - sm.accuracy) * (f.accuracy - sm.accuracy))) < 1e-12
   AND abs(sm.macro_f1_sd * sm.macro_f1_sd * 3 - sum((f.macro_f1 - sm.macro_f1) * (f.macro_f1 - sm.macro_f1))) < 1e-12
   AND abs(sm.pooled_accuracy - sum(f.accuracy * f.n_test) / 32.0) < 1e-12
  FROM cv AS sm JOIN cv AS f ON f.method = sm.method AND f.fold IS NOT NULL
 WHERE sm.fold IS NULL GROUP BY sm.method;

SELECT 'summary rows: the pooled confusion matrix is the sum of the folds''', NOT EXISTS (
  SELECT 1 FROM cv AS sm, json_each(sm.confusion, '$.matrix') AS r, json_each(r.value) AS x
   WHERE sm.fold IS NULL
     AND x.value <> (SELECT sum(json_extract(f.confusion, '$.matrix[' || r.key || '][' || x.key || ']'))
                       FROM cv AS f WHERE f.method = sm.method AND f.fold IS NOT NULL));

SELECT 'a weak configuration (the head alone, 2 states): SVM beats ML here',
       (SELECT accuracy FROM cv WHERE method = 'svm' AND fold IS NULL) >
       (SELECT accuracy FROM cv WHERE method = 'ml' AND fold IS NULL);

-- ---- affect_crossval: leave one performer out ----
CREATE TABLE cvg AS SELECT * FROM affect_crossval('cvs', 'm', 'emotion', '{"states":3,"mixtures":1,"joints":["right_hand","head"],"velocity":true,"max_iter":4,"group":"seed","methods":["knn","svm"],"covariance":"full","frame":"first","descriptors":"none","mirror":false}');

SELECT 'leave-one-group-out: one fold per performer, only the methods asked', count(*) = 2 * 5
   AND group_concat(DISTINCT method) = 'svm,knn'
   AND sum(fold IS NOT NULL AND held_out = CAST(fold AS TEXT) AND n_test = 8 AND n_train = 24) = 8
  FROM cvg;

SELECT 'leave-one-performer-out accuracy of ' || method || ': ' || accuracy, accuracy >= 0.9 AND n_test = 32
  FROM cvg WHERE fold IS NULL;

-- ---- affect_crossval: the functional methods (affect/fda.h), 1-NN in the embedding ----
-- leave one performer out and leave one motion out (the group = the row), against the same
-- folds done by hand with fda_train and fda_classify
CREATE TABLE cvfm(method TEXT, opts TEXT);
INSERT INTO cvfm VALUES ('fpca', '{"method":"fpca"}'), ('ffda', '{"method":"ffda"}'),
  ('fspca', '{"method":"fspca"}'), ('fspca_rbf', '{"method":"fspca","kernel":"rbf","sigma":0.5}'),
  ('fisomap', '{"method":"fisomap","isomap_k":5}');
CREATE TABLE cvf AS SELECT * FROM affect_crossval('cvs', 'm', 'emotion', '{"group":"seed","methods":["fpca","ffda","fspca","fspca_rbf","fisomap"],"dims":2,"basis":20,"sigma":0.5,"isomap_k":5,"joints":["right_hand","head"],"frame":"first","velocity":false}');
CREATE TABLE cvf_hand AS
SELECT x.method, f.s AS fold, count(*) AS n_test,
       avg(fda_classify(f.model, c.m) = c.emotion) AS accuracy, fda_info(f.model) AS info
  FROM cvfm AS x,
       (SELECT x2.method, k.s, (SELECT fda_train(m, emotion, json_patch('{"dims":2,"basis":20,"joints":["right_hand","head"],"frame":"first","velocity":false}', x2.opts)) FROM cvs WHERE seed <> k.s) AS model
          FROM cvfm AS x2, (SELECT DISTINCT seed AS s FROM cvs) AS k) AS f,
       cvs AS c
 WHERE f.method = x.method AND c.seed = f.s
 GROUP BY x.method, f.s;

SELECT 'functional methods: 5 methods × (4 performers + a summary), in method order',
       count(*) = 25 AND group_concat(DISTINCT method) = 'fpca,ffda,fspca,fspca_rbf,fisomap'
  FROM cvf;

SELECT 'functional methods: each fold equals fda_train on the other performers and 1-NN fda_classify: ' || v.method || ' ' || v.fold,
       h.n_test = v.n_test AND v.n_train = 24 AND abs(h.accuracy - v.accuracy) < 1e-12
   AND json_extract(v.params, '$.dims') = json_extract(h.info, '$.dims')
  FROM cvf AS v JOIN cvf_hand AS h ON h.method = v.method AND h.fold = v.fold
 WHERE v.fold IS NOT NULL;

SELECT 'functional methods: the comparison by hand covers every fold of every method', count(*) = 20
  FROM cvf AS v JOIN cvf_hand AS h ON h.method = v.method AND h.fold = v.fold;

SELECT 'functional methods: the supervised ones beat FPCA on this synthetic set (leave one performer out)',
       (SELECT accuracy FROM cvf WHERE method = 'fspca' AND fold IS NULL) >=
       (SELECT accuracy FROM cvf WHERE method = 'fpca' AND fold IS NULL)
   AND (SELECT accuracy FROM cvf WHERE method = 'ffda' AND fold IS NULL) >= 0.5;

-- leave one out: the row as the group; the recognizer's kNN on the same folds
CREATE TABLE cvs1 AS SELECT rowid AS id, * FROM cvs WHERE action = 'wave';
CREATE TABLE cvl AS SELECT * FROM affect_crossval('cvs1', 'm', 'emotion', '{"group":"id","methods":["ml","fspca","ffda"],"dims":3,"basis":20,"states":2,"mixtures":1,"max_iter":2,"joints":["right_hand","head"],"frame":"first","velocity":false,"covariance":"full","descriptors":"none","mirror":false}');

SELECT 'leave one out: one fold per motion for each method, the recognizer''s ml next to the functional ones',
       count(*) = 3 * 17 AND group_concat(DISTINCT method) = 'ml,ffda,fspca'
   AND sum(fold IS NOT NULL AND n_test = 1 AND n_train = 15) = 48
  FROM cvl;

SELECT 'leave one out by hand: ' || v.method || ' ' || v.held_out,
       v.accuracy = (SELECT fda_classify(
                                (SELECT fda_train(m, emotion, json_object('method', v.method, 'dims', 3, 'basis', 20, 'joints', json('["right_hand","head"]'), 'frame', 'first', 'velocity', json('false'))) FROM cvs1 WHERE id <> CAST(v.held_out AS INTEGER)),
                                m) = emotion
                       FROM cvs1 WHERE id = CAST(v.held_out AS INTEGER))
  FROM cvl AS v WHERE v.method IN ('fspca', 'ffda') AND v.fold IS NOT NULL;
-- oom: skip

SELECT * FROM affect_crossval('cvs', 'm', 'emotion', '{"methods":["fspca","fpls"]}');
-- error: affect_crossval: affect_crossval_json: option "methods" must be a non-empty array of "ml", "svm", "knn", "fpca", "ffda", "fspca", "fspca_rbf", "fisomap"

SELECT * FROM affect_crossval('cvs', 'm', 'emotion', '{"methods":["fspca"],"dims":0}');
-- error: affect_crossval: affect_crossval_json: dims must be from 1 to 64

SELECT * FROM affect_crossval('cvs', 'm', 'emotion', '{"methods":["fspca"],"method":"fpca"}');
-- error: affect_crossval: affect_crossval_json: unknown option "method" (expected states, mixtures, covariance, topology, max_jump, start, joints, normalize, scale, up, velocity, frame, root, max_iter, tol, reg, seed, progress, groups, score_normalization, score_clip, svm_c, svm_folds, spca_dims, spca_kernel, spca_sigma, knn_k, grid, folds, descriptors, descriptor_weight, mirror, group, methods, verbose, threads, storage, dims, basis, order, lambda, sigma, ffda_reg, isomap_k, alignment)

-- affect_crossval_json itself (the engine): valid JSON, on 2 motions per class
SELECT 'affect_crossval_json: the rows as JSON', json_valid(j)
   AND json_extract(j, '$.labels') = '["angry","sad"]'
   AND json_extract(j, '$.protocol') = 'stratified k-fold'
   AND json_array_length(j, '$.rows') = 3
  FROM (SELECT affect_crossval_json(motion_slice(m, 0, 9), emotion, NULL, '{"states":1,"mixtures":1,"joints":["head"],"max_iter":1,"svm_c":1,"folds":2,"methods":["ml"]}') AS j
          FROM probe WHERE seed <= 2);

SELECT 'affect_crossval_json: a group column gives leave-one-group-out',
       json_extract(j, '$.protocol') = 'leave-one-group-out' AND json_extract(j, '$.rows[0].held_out') = 'p1'
  FROM (SELECT affect_crossval_json(motion_slice(m, 0, 9), emotion, 'p' || seed, '{"states":1,"mixtures":1,"joints":["head"],"max_iter":1,"svm_c":1,"methods":["svm"]}') AS j
          FROM probe WHERE seed <= 2);

CREATE VIEW cv_view AS SELECT * FROM affect_crossval('cvs', 'm', 'emotion');
SELECT * FROM cv_view;
-- error: unsafe use of virtual table "affect_crossval"

-- ---- NULLs and empty input ----
SELECT 'NULL in gives NULL out',
       affect_classify(NULL, m) IS NULL AND affect_classify(model, NULL) IS NULL
   AND affect_classify(NULL, m, 'knn') IS NULL AND affect_scores(NULL, m) IS NULL
   AND affect_scores(model, NULL) IS NULL AND fisher_score(NULL, m) IS NULL
   AND fisher_score(model, NULL) IS NULL AND affect_embed(NULL, m) IS NULL
   AND affect_embed(model, NULL) IS NULL AND affect_info(NULL) IS NULL
   AND affect_classify(model, m, NULL) = affect_classify(model, m, 'svm')
  FROM small, probe WHERE seed = 4 AND emotion = 'angry';

SELECT affect_train(m, emotion) IS NULL FROM s WHERE seed > 100;
-- expect: 1

SELECT affect_train(m, NULL) IS NULL FROM probe WHERE seed = 1;
-- expect: 1

SELECT 'rows whose label or motion is NULL are skipped',
       (SELECT affect_train(x, label, '{"states":2,"mixtures":1,"joints":["right_hand"],"max_iter":2,"svm_c":1,"spca_dims":1,"knn_k":1,"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false}')
          FROM (SELECT m AS x, NULL AS label FROM probe WHERE seed = 4
                UNION ALL SELECT NULL, 'happy'
                UNION ALL SELECT m, emotion FROM probe WHERE seed <= 3)) = model
  FROM small;
-- oom: skip

SELECT 'two classifiers alternating row by row (the per-function cache follows the BLOB)',
       group_concat(label, ',') = 'sad,10,sad,10'
  FROM (SELECT affect_classify(v.model, p.m, 'ml') AS label
          FROM probe AS p, (SELECT 1 AS o, model FROM small UNION ALL SELECT 2, model FROM numeric) AS v
         WHERE p.emotion = 'sad' AND p.seed IN (1, 2) ORDER BY p.seed, v.o);

-- ---- statements stopped early free the aggregate (checked for leaks in the --oom mode) ----
SELECT seed, length(affect_train(motion_slice(m, 0, 9), emotion, '{"states":1,"mixtures":1,"joints":["head"],"max_iter":1,"svm_c":1,"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false}'))
  FROM probe WHERE seed <= 2 GROUP BY seed LIMIT 1;
-- expect: 1

SELECT affect_train(m, emotion, CASE WHEN seed = 2 THEN '{"states":2}' ELSE '{"states":3}' END) FROM probe;
-- error: affect_train: options must be the same on every row

-- ---- errors ----
SELECT affect_train(m, emotion) FROM probe WHERE emotion = 'sad' AND seed <= 2;
-- error: affect_train: need motions of at least 2 labels, got 1 ("sad")

SELECT affect_train(m, CASE WHEN seed = 2 THEN x'00' ELSE emotion END, '{"states":1}') FROM probe;
-- error: affect_train: row 3: label must be text or a number, got a BLOB

SELECT affect_train(m, '', '{"states":1}') FROM probe;
-- error: affect_train: row 1: label must not be empty or contain NUL

SELECT affect_train('x', 'sad');
-- error: affect_train: argument 1 must be a motion BLOB, got text

SELECT affect_train(m, emotion, '{"svm":1,"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"states":7,"mixtures":4,"max_iter":50}') FROM probe;
-- error: affect_train: unknown option "svm" (expected states, mixtures, covariance, topology, max_jump, start, joints, normalize, scale, up, velocity, frame, root, max_iter, tol, reg, seed, progress, groups, score_normalization, score_clip, svm_c, svm_folds, spca_dims, spca_kernel, spca_sigma, knn_k, grid, descriptors, descriptor_weight, mirror, threads, storage)

SELECT affect_train(m, emotion, '{"svm_c":0,"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"states":7,"mixtures":4,"max_iter":50}') FROM probe;
-- error: affect_train: option "svm_c" must be a positive number or "auto"

SELECT affect_train(m, emotion, '{"svm_c":"big","covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"states":7,"mixtures":4,"max_iter":50}') FROM probe;
-- error: affect_train: option "svm_c" must be a positive number or "auto"

SELECT affect_train(m, emotion, '{"svm_folds":1,"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"states":7,"mixtures":4,"max_iter":50}') FROM probe;
-- error: affect_train: svm_folds must be at least 2

SELECT affect_train(m, emotion, '{"groups":[],"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"states":7,"mixtures":4,"max_iter":50}') FROM probe;
-- error: affect_train: option "groups" must be "all" or a non-empty array of group names (start, transitions, weights, means, covariances)

SELECT affect_train(m, emotion, '{"groups":"means","covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"states":7,"mixtures":4,"max_iter":50}') FROM probe;
-- error: affect_train: option "groups" must be "all" or a non-empty array of group names (start, transitions, weights, means, covariances)

SELECT affect_train(m, emotion, '{"groups":["means",1],"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"states":7,"mixtures":4,"max_iter":50}') FROM probe;
-- error: affect_train: option "groups" must be "all" or a non-empty array of group names (start, transitions, weights, means, covariances)

SELECT affect_train(m, emotion, '{"groups":["means","variances"],"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"states":7,"mixtures":4,"max_iter":50}') FROM probe;
-- error: affect_train: option "groups": unknown group "variances" (start, transitions, weights, means, covariances)

SELECT affect_train(m, emotion, '{"groups":["start"],"states":2,"mixtures":1,"joints":["head"],"max_iter":1,"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false}') FROM probe;
-- error: affect_train: motion 0: Fisher score under the HMM of class "angry": start scores need a model with a learned start

SELECT affect_train(m, emotion, '{"score_normalization":"minmax","covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"states":7,"mixtures":4,"max_iter":50}') FROM probe;
-- error: affect_train: option "score_normalization" must be one of "zscore", "none", got "minmax"

SELECT affect_train(m, emotion, '{"score_clip":-1,"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"states":7,"mixtures":4,"max_iter":50}') FROM probe;
-- error: affect_train: score_clip must be a finite number, 0 or more (0: no limit)

SELECT affect_train(m, emotion, '{"spca_dims":0,"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"states":7,"mixtures":4,"max_iter":50}') FROM probe;
-- error: affect_train: spca_dims must be at least 1

SELECT affect_train(m, emotion, '{"spca_kernel":"poly","covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"states":7,"mixtures":4,"max_iter":50}') FROM probe;
-- error: affect_train: option "spca_kernel" must be one of "linear", "rbf", got "poly"

SELECT affect_train(m, emotion, '{"spca_sigma":0,"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"states":7,"mixtures":4,"max_iter":50}') FROM probe;
-- error: affect_train: spca_sigma must be a positive finite number

SELECT affect_train(m, emotion, '{"knn_k":0,"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"states":7,"mixtures":4,"max_iter":50}') FROM probe;
-- error: affect_train: knn_k must be at least 1

SELECT affect_train(m, emotion, '{"knn_k":2.5,"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"states":7,"mixtures":4,"max_iter":50}') FROM probe;
-- error: affect_train: option "knn_k" must be a whole number from 0 to 4294967295, got 2.5

SELECT affect_train(m, emotion, '{"grid":[1],"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"states":7,"mixtures":4,"max_iter":50}') FROM probe;
-- error: affect_train: option "grid" must be an object, got array

SELECT affect_train(m, emotion, '{"grid":{"k":[1]},"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"states":7,"mixtures":4,"max_iter":50}') FROM probe;
-- error: affect_train: option "grid": unknown key "k" (spca_dims, spca_sigma, knn_k, folds)

SELECT affect_train(m, emotion, '{"grid":{"knn_k":[]},"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"states":7,"mixtures":4,"max_iter":50}') FROM probe;
-- error: affect_train: option "grid": "knn_k" must be an array of 1 to 128 numbers

SELECT affect_train(m, emotion, '{"grid":{"spca_sigma":["a"]},"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"states":7,"mixtures":4,"max_iter":50}') FROM probe;
-- error: affect_train: option "grid": "spca_sigma" must be an array of 1 to 128 numbers

SELECT affect_train(m, emotion, '{"grid":{"spca_dims":3},"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"states":7,"mixtures":4,"max_iter":50}') FROM probe;
-- error: affect_train: option "grid": "spca_dims" must be an array of 1 to 128 numbers

SELECT affect_train(m, emotion, '{"grid":{"knn_k":[1,0]},"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"states":7,"mixtures":4,"max_iter":50}') FROM probe;
-- error: affect_train: grid knn_k must be whole numbers of at least 1

SELECT affect_train(m, emotion, '{"grid":{"spca_dims":[1.5]},"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"states":7,"mixtures":4,"max_iter":50}') FROM probe;
-- error: affect_train: grid spca_dims must be whole numbers of at least 1

SELECT affect_train(m, emotion, '{"grid":{"spca_sigma":[0.5,-1]},"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"states":7,"mixtures":4,"max_iter":50}') FROM probe;
-- error: affect_train: grid spca_sigma must be positive finite numbers

SELECT affect_train(m, emotion, '{"grid":{"folds":1},"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"states":7,"mixtures":4,"max_iter":50}') FROM probe;
-- error: affect_train: option "grid": "folds" must be a whole number from 2 to 1000

SELECT affect_train(m, emotion, '{"states":0,"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"mixtures":4,"max_iter":50}') FROM probe;
-- error: affect_train: states must be between 1 and 256

SELECT affect_train(m, emotion, '{"states":25,"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"mixtures":4,"max_iter":50}') FROM probe;
-- error: affect_train: row 1: the motion has 20 frames; 25 states need at least 25

SELECT affect_classify('x', m) FROM probe WHERE seed = 1;
-- error: affect_classify: argument 1 must be a classifier BLOB (from affect_train), got text

SELECT affect_scores(42, m) FROM probe WHERE seed = 1;
-- error: affect_scores: argument 1 must be a classifier BLOB (from affect_train), got integer

SELECT fisher_score(model, 'm') FROM small;
-- error: fisher_score: argument 2 must be a motion BLOB, got text

SELECT affect_embed(model, model) FROM small;
-- error: affect_embed: argument 2 is not a valid motion: not a motion (bad magic bytes at offset 0)

SELECT affect_classify(model, m, 'svn') FROM small, probe WHERE seed = 1;
-- error: affect_classify: method must be 'svm', 'knn' or 'ml', got 'svn'

SELECT affect_classify(model, m, 2) FROM small, probe WHERE seed = 1;
-- error: affect_classify: method must be 'svm', 'knn' or 'ml', got '2'

SELECT affect_info(x'00');
-- error: affect_info: argument 1 is not a valid classifier: truncated: 1 bytes is shorter than the classifier header

SELECT affect_info(m) FROM probe WHERE seed = 1;
-- error: affect_info: argument 1 is not a valid classifier: not a classifier (bad magic bytes at offset 0)

SELECT affect_info(CAST(substr(model, 1, 1000) || CASE WHEN substr(model, 1001, 1) = x'00' THEN x'01' ELSE x'00' END ||
                        substr(model, 1002) AS BLOB)) FROM small;
-- error: affect_info: argument 1 is not a valid classifier: classifier checksum mismatch: the BLOB is corrupt

SELECT affect_classify(substr(model, 1, length(model) - 1), m) FROM small, probe WHERE seed = 1;
-- error: affect_classify: argument 1 is not a valid classifier: classifier checksum mismatch: the BLOB is corrupt

SELECT affect_scores(hmm_train(m, '{"states":2,"mixtures":1,"joints":["head"],"max_iter":1}'), m) FROM probe WHERE seed = 1;
-- error: affect_scores: argument 1 is not a valid classifier: not a classifier (bad magic bytes at offset 0)

SELECT affect_classify(model, motion_select(m, '["Hips","Chest","Head","UpperArm_L","UpperArm_R"]')) FROM small, probe WHERE seed = 1;
-- error: affect_classify: no joint of the motion has the right_hand role (used by the model)

SELECT * FROM affect_crossval();
-- error: affect_crossval: argument 1 is required, as in SELECT * FROM affect_crossval('motions', 'motion', 'emotion', '{"folds":10}')

SELECT * FROM affect_crossval('cvs', 'm');
-- error: affect_crossval: argument 3 is required, as in SELECT * FROM affect_crossval('motions', 'motion', 'emotion', '{"folds":10}')

SELECT * FROM affect_crossval(3, 'm', 'emotion');
-- error: affect_crossval: argument 1 (table) must be a name, as in SELECT * FROM affect_crossval('motions', 'motion', 'emotion', '{"folds":10}')

SELECT * FROM affect_crossval('cvs', NULL, 'emotion');
-- error: affect_crossval: argument 2 (motion column) must be a name, as in SELECT * FROM affect_crossval('motions', 'motion', 'emotion', '{"folds":10}')

SELECT * FROM affect_crossval('nowhere', 'm', 'emotion');
-- error: affect_crossval: no such table: nowhere

SELECT * FROM affect_crossval('probe', 'motion', 'emotion');
-- error: affect_crossval: no such column: t.motion

SELECT * FROM affect_crossval('probe', 'm', 'label');
-- error: affect_crossval: no such column: t.label

SELECT * FROM affect_crossval('probe', 'm', 'emotion', '{"group":"performer","covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"states":7,"mixtures":4,"max_iter":50}');
-- error: affect_crossval: no such column: t.performer

SELECT * FROM affect_crossval('probe', 'emotion', 'emotion');
-- error: affect_crossval: affect_crossval_json: argument 1 must be a motion BLOB, got text

SELECT * FROM affect_crossval('probe', 'm', 'm');
-- error: affect_crossval: affect_crossval_json: row 1: label must be text or a number, got a BLOB

SELECT * FROM affect_crossval('probe', 'm', 'emotion', '{"folds":1,"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"states":7,"mixtures":4,"max_iter":50}');
-- error: affect_crossval: affect_crossval_json: option "folds" must be from 2 to 1024, got 1

SELECT * FROM affect_crossval('probe', 'm', 'emotion', '{"methods":["svm","lda"],"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"states":7,"mixtures":4,"max_iter":50}');
-- error: affect_crossval: affect_crossval_json: option "methods" must be a non-empty array of "ml", "svm", "knn", "fpca", "ffda", "fspca", "fspca_rbf", "fisomap"

SELECT * FROM affect_crossval('probe', 'm', 'emotion', '{"group":1,"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"states":7,"mixtures":4,"max_iter":50}');
-- error: affect_crossval: affect_crossval_json: option "group" must be a column name

SELECT * FROM affect_crossval('probe', 'm', 'emotion', '{"fold":3,"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"states":7,"mixtures":4,"max_iter":50}');
-- error: affect_crossval: affect_crossval_json: unknown option "fold" (expected states, mixtures, covariance, topology, max_jump, start, joints, normalize, scale, up, velocity, frame, root, max_iter, tol, reg, seed, progress, groups, score_normalization, score_clip, svm_c, svm_folds, spca_dims, spca_kernel, spca_sigma, knn_k, grid, folds, descriptors, descriptor_weight, mirror, group, methods, verbose, threads, storage, dims, basis, order, lambda, sigma, ffda_reg, isomap_k, alignment)

SELECT * FROM affect_crossval('probe', 'm', 'emotion', '{"knn_k":0,"covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"states":7,"mixtures":4,"max_iter":50}');
-- error: affect_crossval: affect_crossval_json: knn_k must be at least 1

SELECT * FROM affect_crossval('probe', 'm', 'emotion', '[]');
-- error: affect_crossval: affect_crossval_json: options (argument 4) must be a JSON object, got array

CREATE TABLE lonely AS SELECT m, emotion, CASE WHEN seed = 1 THEN NULL ELSE seed END AS performer FROM probe WHERE seed <= 2;
SELECT * FROM affect_crossval('lonely', 'm', 'emotion', '{"group":"performer","covariance":"full","frame":"first","velocity":false,"descriptors":"none","mirror":false,"states":7,"mixtures":4,"max_iter":50}');
-- error: affect_crossval: affect_crossval_json: the group is NULL for 2 of 4 motions

SELECT * FROM affect_crossval('lonely', 'm', '''sad''');
-- error: affect_crossval: no such column: t.'sad'

CREATE TABLE onelabel AS SELECT m, 'sad' AS emotion FROM probe WHERE seed <= 2;
SELECT * FROM affect_crossval('onelabel', 'm', 'emotion');
-- error: affect_crossval: affect_crossval_json: need motions of at least 2 labels, got 1 ("sad")
