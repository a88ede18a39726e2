-- hmm_eval.sql — maximum-likelihood emotion recognition with one HMM per emotion on the real
-- corpus (SCIENCE.md §2; thesis: 74 % full-body, 79 % hand-arm), printed as a Markdown table.
--
--   ./run.sh demo        # builds demo.db with the corpus, then:
--   sqlite3 demo.db -cmd '.load ./build/affect' < sql/hmm_eval.sql
--
-- Data: angry, happy, sad and normal over the ten contents recorded in every style (44 motions,
-- 11 per emotion). Protocols:
--   loco  leave-one-content-out: train on 9 contents, test on the 10th (a kinematically unseen
--         action; 10 folds, the walk fold tests 8 motions);
--   10cv  10-fold stratified cross-validation: within each emotion, motions are ordered by a
--         seeded hash of their name and dealt to folds 0..9 in turn (seed 7).
-- Decision: the label whose model gives the largest log P(x | Λ). Dividing by the frame count
-- would not change it (all four scores of a motion share its length), so per-frame likelihoods
-- do not remove the duration cue for this decision (the corpus's normal clips are short and its
-- sad clips long, see its SOURCE.md): durations reach the decision only through the models'
-- state durations.
-- Features: normalized (first-frame translation and heading removed, scaled by the right arm),
-- positions and velocities of the given joints. Configurations are listed in `configs`.
.headers off
.mode list

DROP TABLE IF EXISTS temp.eval_data;
CREATE TEMP TABLE eval_data AS
SELECT id, name, content, emotion, motion,
       (row_number() OVER (PARTITION BY emotion
                           ORDER BY (unicode(substr(name, -5)) * 7919 + length(name) * 104729
                                     + id * 2654435761 + 7) % 1000003, name) - 1) % 10 AS cv_fold
  FROM motions
 WHERE source <> 'synth' AND emotion IN ('angry', 'happy', 'sad', 'normal')
   AND content IN ('walk', 'run', 'dash', 'walk-back', 'walk-left', 'walk-right',
                   'bow', 'bye', 'byebye', 'guide');

DROP TABLE IF EXISTS temp.configs;
CREATE TEMP TABLE configs(name TEXT, options TEXT);
INSERT INTO configs VALUES
 ('end-effectors + torso, 3 states × 1', '{"states":3,"mixtures":1,"joints":["pelvis","chest","head","left_hand","right_hand","left_foot","right_foot"],"velocity":true,"max_iter":20,"seed":1}'),
 ('end-effectors + torso, 5 states × 2', '{"states":5,"mixtures":2,"joints":["pelvis","chest","head","left_hand","right_hand","left_foot","right_foot"],"velocity":true,"max_iter":20,"seed":1}'),
 ('end-effectors + torso, 7 states × 4', '{"states":7,"mixtures":4,"covariance":"diag","joints":["pelvis","chest","head","left_hand","right_hand","left_foot","right_foot"],"velocity":true,"max_iter":20,"seed":1}'),
 ('all joints, 5 states × 1', '{"states":5,"mixtures":1,"covariance":"diag","velocity":true,"max_iter":20,"seed":1}');

DROP TABLE IF EXISTS temp.folds;
CREATE TEMP TABLE folds AS
SELECT 'loco' AS protocol, content AS fold FROM eval_data GROUP BY content
UNION ALL
SELECT '10cv', CAST(cv_fold AS TEXT) FROM eval_data GROUP BY cv_fold;

-- one model per configuration, protocol, fold and emotion, trained without the fold
DROP TABLE IF EXISTS temp.models;
CREATE TEMP TABLE models AS
SELECT c.name AS config, f.protocol, f.fold, d.emotion,
       hmm_train(d.motion, c.options) AS model
  FROM configs AS c, folds AS f, eval_data AS d
 WHERE (f.protocol = 'loco' AND d.content <> f.fold)
    OR (f.protocol = '10cv' AND CAST(d.cv_fold AS TEXT) <> f.fold)
 GROUP BY c.name, f.protocol, f.fold, d.emotion;

-- every test motion scored under its fold's four models
DROP TABLE IF EXISTS temp.scores;
CREATE TEMP TABLE scores AS
SELECT m.config, m.protocol, m.fold, d.name, d.emotion AS truth, m.emotion AS label,
       hmm_loglik(m.model, d.motion) AS ll
  FROM models AS m JOIN eval_data AS d
    ON (m.protocol = 'loco' AND d.content = m.fold)
    OR (m.protocol = '10cv' AND CAST(d.cv_fold AS TEXT) = m.fold);

DROP TABLE IF EXISTS temp.predictions;
CREATE TEMP TABLE predictions AS
SELECT config, protocol, name, truth,
       (SELECT s2.label FROM scores AS s2 WHERE s2.config = s.config AND s2.protocol = s.protocol
           AND s2.name = s.name ORDER BY s2.ll DESC, s2.label LIMIT 1) AS by_total
  FROM scores AS s GROUP BY config, protocol, name;

SELECT '| configuration | protocol | ML accuracy |';
SELECT '|---|---|---:|';
SELECT printf('| %s | %s | %.0f %% (%d/%d) |', config,
              CASE protocol WHEN 'loco' THEN 'leave one content out' ELSE '10-fold stratified' END,
              100.0 * sum(by_total = truth) / count(*), sum(by_total = truth), count(*))
  FROM predictions GROUP BY config, protocol ORDER BY config, protocol DESC;

SELECT '';
SELECT 'Confusion (rows: truth; columns: predicted), best configuration, leave one content out:';
WITH best AS (
    SELECT config FROM predictions WHERE protocol = 'loco'
     GROUP BY config ORDER BY sum(by_total = truth) DESC, config LIMIT 1)
SELECT printf('%-7s angry %2d  happy %2d  normal %2d  sad %2d', truth,
              sum(by_total = 'angry'), sum(by_total = 'happy'), sum(by_total = 'normal'),
              sum(by_total = 'sad'))
  FROM predictions WHERE protocol = 'loco' AND config = (SELECT config FROM best)
 GROUP BY truth ORDER BY truth;
