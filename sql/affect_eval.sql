-- affect_eval.sql — emotion recognition on the real corpus with the hybrid recognizer
-- (SCIENCE.md §3; thesis Table 4.2: ML 74 %, Fisher + SVM 76 %, Fisher + sPCA + kNN 77 %
-- full-body), printed as Markdown tables.
--
--   ./run.sh demo        # builds demo.db with the corpus, then:
--   OPENBLAS_NUM_THREADS=1 sqlite3 demo.db -cmd '.load ./build/affect' < sql/affect_eval.sql
--
-- Data: angry, happy, sad and normal over the ten contents recorded in every style (44 motions,
-- 11 per emotion); then the 7 affect-related styles (angry, happy, sad, normal, proud,
-- not-confident, tired; 77 motions) as a harder task. Protocols, both by affect_crossval:
--   10-fold   stratified 10-fold cross-validation, seed 7 (the defaults row: seed 1);
--   LOCO      leave one content out (10 folds; the held-out action was never seen in training).
-- The three methods are scored on the same folds by the same classifiers (ML = the class HMM
-- with the largest log-likelihood). Cells: mean ± sample sd of the per-fold accuracies, then
-- the pooled accuracy (correct / all motions). Configurations are listed in `configs`: first
-- the defaults (no option: the body frame, 5 states × 1 diagonal, mirror images, kinematic
-- summaries; chosen in docs/EVALUATION.md, "Choosing the defaults"), then the earlier rows with
-- the observations they were published with ("frame": "first", no descriptors, no mirror
-- images, so that their numbers still reproduce); the last one chooses sPCA dims, RBF σ and k
-- by nested 5-fold cross-validation inside each training fold. The confusion matrices and the
-- 7-style task use the defaults. Folds run two at a time ("threads": 2; the results do not
-- depend on it): about a minute on the 2-core machine with OPENBLAS_NUM_THREADS=1 (OpenBLAS's
-- own threads only compete).
.headers off
.mode list

DROP TABLE IF EXISTS temp.eval_data;
CREATE TEMP TABLE eval_data AS
SELECT id, name, content, emotion, motion FROM motions
 WHERE source <> 'synth' AND emotion IN ('angry', 'happy', 'sad', 'normal')
   AND content IN ('walk', 'run', 'dash', 'walk-back', 'walk-left', 'walk-right',
                   'bow', 'bye', 'byebye', 'guide');

DROP TABLE IF EXISTS temp.eval_data7;
CREATE TEMP TABLE eval_data7 AS
SELECT id, name, content, emotion, motion FROM motions
 WHERE source <> 'synth'
   AND emotion IN ('angry', 'happy', 'sad', 'normal', 'proud', 'not-confident', 'tired')
   AND content IN ('walk', 'run', 'dash', 'walk-back', 'walk-left', 'walk-right',
                   'bow', 'bye', 'byebye', 'guide');

DROP TABLE IF EXISTS temp.configs;
CREATE TEMP TABLE configs(k INTEGER, name TEXT, options TEXT);
INSERT INTO configs VALUES
 (0, 'defaults: body frame, 5 states × 1, diagonal, mirror images, kinematic summaries', '{}'),
 (1, 'all joints, 5 states × 1, diagonal', '{"states":5,"mixtures":1,"covariance":"diag","velocity":true,"max_iter":20,"seed":7,"frame":"first","descriptors":"none","mirror":false}'),
 (2, 'end-effectors + torso, 5 states × 2, full', '{"states":5,"mixtures":2,"joints":["pelvis","chest","head","left_hand","right_hand","left_foot","right_foot"],"velocity":true,"max_iter":20,"seed":7,"covariance":"full","frame":"first","descriptors":"none","mirror":false}'),
 (3, 'end-effectors + torso, 7 states × 4, full (the thesis''s)', '{"states":7,"mixtures":4,"joints":["pelvis","chest","head","left_hand","right_hand","left_foot","right_foot"],"velocity":true,"max_iter":20,"seed":7,"covariance":"full","frame":"first","descriptors":"none","mirror":false}'),
 (4, 'all joints, 5 states × 1, diagonal, nested grid', '{"states":5,"mixtures":1,"covariance":"diag","velocity":true,"max_iter":20,"seed":7,"grid":{"spca_dims":[1,2,3],"spca_sigma":[0.25,0.5,1,2,5,10,25],"knn_k":[1,3,5,7,9,11,13,15]},"frame":"first","descriptors":"none","mirror":false}');

DROP TABLE IF EXISTS temp.results;
CREATE TEMP TABLE results AS
SELECT c.k, c.name, '10-fold' AS protocol, r.*
  FROM configs AS c, affect_crossval('eval_data', 'motion', 'emotion',
                                     json_set(c.options, '$.folds', 10, '$.threads', 2)) AS r
UNION ALL
SELECT c.k, c.name, 'LOCO', r.*
  FROM configs AS c, affect_crossval('eval_data', 'motion', 'emotion',
                                     json_set(c.options, '$.group', 'content', '$.threads', 2))
       AS r;

SELECT '| configuration | protocol | HMM + ML | Fisher + SVM | Fisher + sPCA + kNN |';
SELECT '|---|---|---:|---:|---:|';
SELECT printf('| %s | %s | %s | %s | %s |', name, protocol,
              max(CASE method WHEN 'ml' THEN cell END), max(CASE method WHEN 'svm' THEN cell END),
              max(CASE method WHEN 'knn' THEN cell END))
  FROM (SELECT k, name, protocol, method,
               printf('%.0f ± %.0f %% (%.0f %%)', 100 * accuracy, 100 * accuracy_sd,
                      100 * pooled_accuracy) AS cell
          FROM results WHERE fold IS NULL)
 GROUP BY k, protocol ORDER BY k, protocol;
SELECT '| thesis, full-body (183 motions, 13 performers, 10-fold) | 10-fold | 74 ± 3.2 % | 76 ± 3.1 % | 77 ± 3.1 % |';
SELECT '| thesis, full-body, leave one subject out (balanced accuracy) | LOSO | 70 % | 71 % | 72 % |';
SELECT '| thesis, hand-arm (151 motions, 1 actor, 6 emotions) | 10-fold | 79 % | 97 % | 96 % |';

-- Fisher + SVM against ML, fold by fold
SELECT '';
SELECT 'Folds where Fisher + SVM beats / ties / loses to ML (same folds, same classifiers):';
SELECT '';
SELECT '| configuration | protocol | better | tied | worse |';
SELECT '|---|---|---:|---:|---:|';
SELECT printf('| %s | %s | %d | %d | %d |', s.name, s.protocol, sum(s.accuracy > m.accuracy),
              sum(s.accuracy = m.accuracy), sum(s.accuracy < m.accuracy))
  FROM results AS s JOIN results AS m
    ON m.k = s.k AND m.protocol = s.protocol AND m.fold = s.fold AND m.method = 'ml'
 WHERE s.method = 'svm' AND s.fold IS NOT NULL
 GROUP BY s.k, s.protocol ORDER BY s.k, s.protocol;

-- confusion matrices of the first configuration, pooled over the folds
SELECT '';
SELECT 'Pooled confusion matrices, ' || (SELECT name FROM configs WHERE k = 0)
       || ' (rows: truth; columns: predicted, in the order of the labels):';
SELECT '';
SELECT printf('- %s, %s: labels %s, %s', protocol, method,
              json_extract(confusion, '$.labels'), json_extract(confusion, '$.matrix'))
  FROM results WHERE k = 0 AND fold IS NULL ORDER BY protocol, method;

-- the choices of the nested grid
SELECT '';
SELECT 'Nested grid (configuration 4): sPCA dims / σ / k chosen per fold: '
       || group_concat(printf('%s', json_extract(params, '$.spca_dims') || '/'
                               || json_extract(params, '$.spca_sigma') || '/'
                               || json_extract(params, '$.knn_k')), ', ')
  FROM results WHERE k = 4 AND method = 'knn' AND fold IS NOT NULL AND protocol = '10-fold';

-- the harder task: 7 styles
DROP TABLE IF EXISTS temp.results7;
CREATE TEMP TABLE results7 AS
SELECT '10-fold' AS protocol, r.*
  FROM affect_crossval('eval_data7', 'motion', 'emotion',
                       json_set((SELECT options FROM configs WHERE k = 0), '$.folds', 10,
                                '$.threads', 2)) AS r
UNION ALL
SELECT 'LOCO', r.*
  FROM affect_crossval('eval_data7', 'motion', 'emotion',
                       json_set((SELECT options FROM configs WHERE k = 0), '$.group',
                                'content', '$.threads', 2)) AS r;
SELECT '';
SELECT 'Seven styles (angry, happy, sad, normal, proud, not-confident, tired; 77 motions; chance 14 %), '
       || (SELECT name FROM configs WHERE k = 0) || ':';
SELECT '';
SELECT '| protocol | HMM + ML | Fisher + SVM | Fisher + sPCA + kNN |';
SELECT '|---|---:|---:|---:|';
SELECT printf('| %s | %s | %s | %s |', protocol,
              max(CASE method WHEN 'ml' THEN cell END), max(CASE method WHEN 'svm' THEN cell END),
              max(CASE method WHEN 'knn' THEN cell END))
  FROM (SELECT protocol, method,
               printf('%.0f ± %.0f %% (%.0f %%)', 100 * accuracy, 100 * accuracy_sd,
                      100 * pooled_accuracy) AS cell
          FROM results7 WHERE fold IS NULL)
 GROUP BY protocol ORDER BY protocol;
