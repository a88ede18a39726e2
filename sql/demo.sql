-- demo.sql — the demo's summary and its HTML page (run by `./run.sh demo` after the corpus
-- is built; see README). Prints what the database holds, then writes demo.html with SVG film
-- strips of the synthetic corpus and, when it was imported, of the real one; animations
-- (motion_svg's "animate", motion_svg_group: the source, generated and real motions side by
-- side), a walk's top view, the salient joints as a heat map (affect_heatmap) and the emotion
-- HMMs' key postures labelled by state. tests/client/chromium_test.sh renders the page in
-- headless Chromium.
--
--   sqlite3 demo.db -cmd '.load ./build/affect' < sql/demo.sql
.headers on
.mode column

.print
.print '== what demo.db holds =='
SELECT source, count(*) AS motions, sum(frames) AS frames,
       printf('%.1f', sum(frames / fps)) AS seconds
  FROM motions GROUP BY source ORDER BY source;

.print
.print '== the four emotions, by source =='
SELECT source, emotion, count(*) AS motions,
       printf('%.2f', avg(frames / fps)) AS mean_seconds
  FROM motions
 WHERE emotion IN ('angry', 'happy', 'sad', 'normal', 'neutral')
 GROUP BY source, emotion ORDER BY source, emotion;

.print
.print '== one motion of each source =='
SELECT name, motion_joints(motion) AS joints, motion_frames(motion) AS frames,
       motion_fps(motion) AS fps, printf('%.2f', motion_duration(motion)) AS seconds,
       json_extract(motion_info(motion), '$.unit') AS unit
  FROM motions WHERE id IN (SELECT min(id) FROM motions GROUP BY source);

.print
.print '== body-part roles resolved from joint names =='
SELECT key AS role, value AS joint
  FROM motions, json_each(motion_roles(motion))
 WHERE motions.id = (SELECT min(id) FROM motions WHERE source <> 'synth'
                     UNION ALL SELECT min(id) FROM motions LIMIT 1)
   AND key IN ('pelvis', 'head', 'left_hand', 'right_hand', 'left_foot', 'right_foot');

.print
.print '== highest hand of each synthetic emotion (knock, seed 1; metres) =='
SELECT m.emotion, printf('%.3f', max(p.y)) AS max_right_hand_y
  FROM motions AS m, motion_points(m.motion) AS p
 WHERE m.source = 'synth' AND m.content = 'knock' AND m.performer = 'synth-1' AND p.name = 'Hand_R'
 GROUP BY m.emotion ORDER BY m.emotion;

.print
.print '== Laban Effort by emotion (means; synthetic corpus in m and s) =='
SELECT emotion, printf('%.2f', avg(laban_weight(motion))) AS WeightAll,
       printf('%.1f', avg(laban_time(motion))) AS TimeAll,
       printf('%.0f', avg(laban_flow(motion))) AS FlowAll
  FROM motions WHERE source = 'synth'
 GROUP BY emotion ORDER BY avg(laban_weight(motion)) DESC;

-- A Laban index over one source (the real corpus when imported; units must not be mixed in
-- one index, since distances are standardized over it: the corpus is in cm, motion_synth in m).
CREATE TABLE indexed(id INTEGER PRIMARY KEY, name TEXT, content TEXT, emotion TEXT, motion BLOB);
INSERT INTO indexed
SELECT id, name, content, emotion, motion FROM motions
 WHERE source = coalesce((SELECT source FROM motions WHERE source <> 'synth'
                            AND emotion IN ('angry', 'happy', 'sad', 'normal', 'neutral')
                           GROUP BY source ORDER BY count(*) DESC LIMIT 1), 'synth')
   AND emotion IN ('angry', 'happy', 'sad', 'normal', 'neutral');
CREATE VIRTUAL TABLE motion_laban USING laban(content=indexed, motion=motion, label=emotion);

.print
.print '== Laban nearest neighbours: the 3 angry and the 3 sad motions nearest to a neutral wave =='
SELECT (SELECT name FROM indexed WHERE content IN ('bye', 'wave')
          AND emotion IN ('normal', 'neutral') ORDER BY name LIMIT 1) AS query;
SELECT i.name, l.label, printf('%.3f', l.distance) AS distance
  FROM motion_laban AS l JOIN indexed AS i ON i.id = l.rowid
 WHERE l.query = (SELECT id FROM indexed WHERE content IN ('bye', 'wave')
                    AND emotion IN ('normal', 'neutral') ORDER BY name LIMIT 1)
   AND l.label IN ('angry', 'sad') AND l.k = 3
 ORDER BY l.label, l.distance;

.print
.print "== the thesis's ε-neighbourhood (radius 0.1 on Time and Flow), sad motions =="
SELECT i.name, printf('%.3f', l.distance) AS distance
  FROM motion_laban AS l JOIN indexed AS i ON i.id = l.rowid
 WHERE l.query = (SELECT id FROM indexed WHERE content IN ('bye', 'wave')
                    AND emotion IN ('normal', 'neutral') ORDER BY name LIMIT 1)
   AND l.label = 'sad' AND l.radius = 0.1 AND l.components = '["TimeAll","FlowAll"]';

-- ---- emotion recognition: class HMMs, Fisher scores, SVM, sPCA + kNN (thesis chapter 4) ----
-- trained on the real corpus's four emotions when it was imported, else on motion_synth
DROP TABLE IF EXISTS rec_data;
CREATE TABLE rec_data AS
SELECT id, name, content, emotion, motion FROM motions
 WHERE source <> 'synth' AND emotion IN ('angry', 'happy', 'sad', 'normal')
   AND content IN ('walk', 'run', 'dash', 'walk-back', 'walk-left', 'walk-right',
                   'bow', 'bye', 'byebye', 'guide');
INSERT INTO rec_data
SELECT id, name, content, emotion, motion FROM motions
 WHERE source = 'synth' AND NOT EXISTS (SELECT 1 FROM rec_data);
DROP TABLE IF EXISTS classifiers;
CREATE TABLE classifiers AS
SELECT 'four emotions' AS name,
       affect_train(motion, emotion, '{"threads":2}') AS model  -- the defaults, two threads
  FROM rec_data;

.print
.print '== emotion recognizer (affect_train: HMM per emotion, Fisher scores, SVM, sPCA + kNN) =='
SELECT json_extract(affect_info(model), '$.training_motions') AS motions,
       json_extract(affect_info(model), '$.dimensions.representation') AS dims,
       length(model) AS blob_bytes,
       printf('%.2f', json_extract(affect_info(model), '$.training_accuracy.ml')) AS train_ml,
       printf('%.2f', json_extract(affect_info(model), '$.training_accuracy.svm')) AS train_svm,
       printf('%.2f', json_extract(affect_info(model), '$.training_accuracy.knn_leave_one_out'))
           AS knn_loo
  FROM classifiers;

.print
.print '== the other styles, as the four-emotion classifier sees them (Fisher + SVM) =='
SELECT emotion AS style, group_concat(label || ' ' || n, ', ') AS recognized_as
  FROM (SELECT emotion, affect_classify(c.model, m.motion) AS label, count(*) AS n
          FROM motions AS m, classifiers AS c
         WHERE m.source <> 'synth' AND m.emotion IN ('proud', 'not-confident', 'tired')
           AND json_extract(motion_info(m.motion), '$.names')   -- the training skeleton only
               = (SELECT json_extract(motion_info(motion), '$.names') FROM rec_data LIMIT 1)
         GROUP BY emotion, label ORDER BY emotion, n DESC, label)
 GROUP BY emotion;

-- ---- generation (SCIENCE.md §5): a motion made angry, happy or sad ----
-- The source is a normal "bye" (neutral "wave" on the synthetic corpus); its own content is
-- left out of the generation corpus, so the real recording of that content in the target
-- emotion can serve as ground truth.
DROP TABLE IF EXISTS gen_source;
CREATE TABLE gen_source AS
SELECT id, name, content, emotion, motion FROM indexed
 WHERE content IN ('bye', 'wave') AND emotion IN ('normal', 'neutral') ORDER BY name LIMIT 1;
DROP TABLE IF EXISTS gen_laban;
DROP TABLE IF EXISTS gen_corpus;
CREATE TABLE gen_corpus(id INTEGER PRIMARY KEY, name TEXT, content TEXT, emotion TEXT, motion BLOB);
INSERT INTO gen_corpus SELECT id, name, content, emotion, motion FROM indexed
 WHERE content <> (SELECT content FROM gen_source);
CREATE VIRTUAL TABLE gen_laban USING laban(content=gen_corpus, motion=motion, label=emotion);
DROP TABLE IF EXISTS generated;
CREATE TABLE generated(id INTEGER PRIMARY KEY, source_id INTEGER, target TEXT,
                       strength REAL, motion BLOB, explain TEXT, truth_id INTEGER);
INSERT INTO generated(source_id, target, strength, motion, explain, truth_id)
SELECT s.id, t.value, k.value,
       affect_generate('gen_laban', s.motion, t.value,
                       json_object('source_label', s.emotion, 'strength', k.value)),
       affect_generate_explain('gen_laban', s.motion, t.value,
                               json_object('source_label', s.emotion, 'strength', k.value)),
       (SELECT id FROM indexed WHERE content = s.content AND emotion = t.value ORDER BY name LIMIT 1)
  FROM gen_source AS s, json_each('["angry","happy","sad"]') AS t, json_each('[0.5,1,1.5]') AS k
 WHERE t.value IN (SELECT emotion FROM gen_corpus);

.print
.print '== generation: the source made angry, happy, sad (affect_generate; its content left out of the corpus) =='
SELECT s.name AS source, g.target,
       json_array_length(json_extract(g.explain, '$.components.used')) AS components,
       (SELECT group_concat(a.content || '/' || a.emotion || '→' || b.emotion, ' ')
          FROM json_each(g.explain, '$.pairs') AS p
          JOIN gen_corpus AS a ON a.id = json_extract(p.value, '$.from.rowid')
          JOIN gen_corpus AS b ON b.id = json_extract(p.value, '$.to.rowid')) AS "donor pairs",
       printf('%.1f', json_extract(g.explain, '$.change.posture_deg')) AS "posture°"
  FROM generated AS g JOIN gen_source AS s ON s.id = g.source_id WHERE g.strength = 1
 ORDER BY g.target;

.print
.print '== generated (strengths 0.5, 1, 1.5) vs source vs the real recording in the target emotion =='
SELECT g.target, g.strength, printf('%.4g / %.4g / %.4g', laban_weight(s.motion), laban_weight(g.motion),
                        laban_weight(r.motion)) AS "WeightAll src / gen / real",
       printf('%.4g / %.4g / %.4g', laban_time(s.motion), laban_time(g.motion),
              laban_time(r.motion)) AS "TimeAll src / gen / real",
       printf('%.3f -> %.3f', motion_dtw(s.motion, r.motion), motion_dtw(g.motion, r.motion))
           AS "DTW to real: src -> gen",
       affect_classify(c.model, g.motion) AS recognized
  FROM generated AS g JOIN gen_source AS s ON s.id = g.source_id
  JOIN indexed AS r ON r.id = g.truth_id, classifiers AS c
 ORDER BY g.target, g.strength;

-- ---- the HTML page ----
.headers off
.mode list
.output demo.html
SELECT '<!doctype html><html><head><meta charset="utf-8"><title>sqlite-affect demo</title>'
    || '<style>body{font-family:sans-serif;margin:2em;color:#222}h2{margin-top:2em}'
    || 'figure{display:inline-block;margin:0 1em 1em 0;vertical-align:top}'
    || 'figcaption{font-size:13px;color:#555}</style></head><body>'
    || '<h1>sqlite-affect demo</h1><p>Film strips and animations drawn by <code>motion_svg(motion, options)</code>, '
    || 'straight from <code>demo.db</code>. Blue: left side, red: right side; faint lines: '
    || 'paths of the head, hands and feet; the grey bar under an animation shows its time.</p>';
SELECT '<h2>Synthetic corpus (motion_synth, performer seed 1)</h2>'
    || '<p>One action in four emotions, animated side by side at one scale: '
    || '<code>motion_svg_group(motion, emotion, ''{"animate":true}'')</code>.</p>'
    || motion_svg_group(motion, emotion, '{"animate":true,"size":130,"title":"knock"}')
  FROM (SELECT * FROM motions WHERE source = 'synth' AND performer = 'synth-1' AND content = 'knock'
         ORDER BY CASE emotion WHEN 'neutral' THEN 0 WHEN 'happy' THEN 1 WHEN 'sad' THEN 2 ELSE 3 END);
SELECT '<h3>' || content || '</h3>' || group_concat(
           '<figure>' || motion_svg(motion, json_object(
               'frames', 6, 'size', 110,
               'view', CASE content WHEN 'walk' THEN 'side' WHEN 'bow' THEN 'side' ELSE 'front' END,
               'title', content || ' · ' || emotion))
           || '<figcaption>' || name || '</figcaption></figure>', '')
  FROM (SELECT * FROM motions WHERE source = 'synth' AND performer = 'synth-1'
         ORDER BY content, CASE emotion WHEN 'neutral' THEN 0 WHEN 'happy' THEN 1
                                        WHEN 'sad' THEN 2 ELSE 3 END)
 GROUP BY content ORDER BY content;
SELECT CASE WHEN count(*) > 0 THEN '<h2>Real corpus (Bandai-Namco dataset 1): the same action in four emotions</h2>'
            ELSE '<h2>Real corpus</h2><p>Not imported: pass a folder of BVH files to <code>./run.sh demo</code>.</p>' END
  FROM motions WHERE source <> 'synth';
SELECT '<h3>' || content || '</h3>' || group_concat(
           '<figure>' || motion_svg(motion, json_object(
               'frames', 6, 'size', 110,
               'view', CASE WHEN content LIKE 'walk%' OR content IN ('run', 'dash', 'bow') THEN 'side' ELSE 'front' END,
               'title', content || ' · ' || emotion))
           || '<figcaption>' || name || '</figcaption></figure>', '')
  FROM (SELECT * FROM motions
         WHERE source <> 'synth' AND content IN ('bow', 'bye', 'guide', 'walk')
           AND emotion IN ('angry', 'happy', 'sad', 'normal') AND name NOT LIKE '%\_002' ESCAPE '\'
         ORDER BY content, CASE emotion WHEN 'normal' THEN 0 WHEN 'happy' THEN 1
                                        WHEN 'sad' THEN 2 ELSE 3 END)
 GROUP BY content ORDER BY content;
SELECT '<h2>A walk seen from above</h2><p><code>motion_svg(motion, ''{"view":"top"}'')</code>: '
    || 'each panel is centred on the pelvis and turned so that the walk goes to the right; the grey '
    || 'line is the pelvis''s path, the triangle at the head points where the body faces.</p>'
    || '<figure>' || motion_svg(motion, json_object('view', 'top', 'frames', 6, 'size', 110,
                                'title', 'top · ' || name))
    || '</figure><figure>' || motion_svg(motion, json_object('view', 'top', 'animate', json('true'),
                                'size', 110, 'title', 'animated'))
    || '</figure>'
  FROM (SELECT * FROM motions WHERE content = 'walk' AND emotion IN ('angry', 'neutral')
         ORDER BY source = 'synth', name LIMIT 1);
SELECT '<h2>Generation: the source, the generated motion at three strengths, the real recording (SCIENCE.md §5)</h2>'
    || '<p><code>affect_generate(''gen_laban'', motion, target, json_object(''source_label'', emotion, ''strength'', s))</code>'
    || ' over a laban index that leaves the source''s content out: the emotion''s change, learned '
    || 'from donor pairs of other contents, applied to the source itself (its action, timing and '
    || 'path stay); right: the actor''s own recording of that content in the target emotion '
    || '(ground truth, not used).</p>';
SELECT '<h3>Animated: the source, each target generated at strength 1, and its real recording</h3>'
    || '<p><code>motion_svg_group(motion, caption, ''{"animate":true}'')</code> over the rows '
    || 'source, generated, real: one scale for all, each looping at its own duration.</p>'
    || motion_svg_group(motion, caption, '{"animate":true,"size":120,"view":"front"}')
  FROM (SELECT 0 AS k, 'source · ' || s.emotion AS caption, s.motion FROM gen_source AS s
        UNION ALL
        SELECT 1 + 2 * t.rank, 'generated · ' || g.target, g.motion
          FROM generated AS g JOIN (SELECT target, row_number() OVER (ORDER BY target) AS rank
                                      FROM generated GROUP BY target) AS t USING (target)
         WHERE g.strength = 1
        UNION ALL
        SELECT 2 + 2 * t.rank, 'real · ' || g.target, r.motion
          FROM generated AS g JOIN indexed AS r ON r.id = g.truth_id
          JOIN (SELECT target, row_number() OVER (ORDER BY target) AS rank
                  FROM generated GROUP BY target) AS t USING (target)
         WHERE g.strength = 1
         ORDER BY k);
SELECT '<h3>' || s.name || ' → ' || g1.target || '</h3>'
    || '<figure>' || motion_svg(s.motion, json_object('frames', 6, 'size', 110, 'view', 'front',
                                 'title', 'source · ' || s.emotion))
    || '<figcaption>source: ' || s.name || '</figcaption></figure>'
    || (SELECT group_concat('<figure>' || motion_svg(g.motion, json_object('frames', 6, 'size', 110,
                               'view', 'front', 'title', g.target || ' · strength ' || g.strength))
                || '<figcaption>generated, strength ' || g.strength || ' (recognized: '
                || affect_classify(c.model, g.motion) || ')</figcaption></figure>', '')
          FROM (SELECT * FROM generated WHERE source_id = g1.source_id AND target = g1.target
                 ORDER BY strength) AS g)
    || coalesce('<figure>' || motion_svg(r.motion, json_object('frames', 6, 'size', 110, 'view', 'front',
                                 'title', 'real · ' || g1.target))
                || '<figcaption>real: ' || r.name || '</figcaption></figure>', '')
  FROM generated AS g1 JOIN gen_source AS s ON s.id = g1.source_id
  LEFT JOIN indexed AS r ON r.id = g1.truth_id, classifiers AS c
 WHERE g1.strength = 1
 ORDER BY g1.target;
SELECT '<h2>Laban Weight and Time by emotion (thesis Fig. 5.1)</h2><p>Each point is a motion of the '
    || 'indexed source; crosses show each emotion''s mean ± 1 sd (log axes). Drawn by '
    || '<code>laban_plot(laban_weight(motion), laban_time(motion), emotion, …)</code>.</p>'
    || laban_plot(WeightAll, TimeAll, label,
                  '{"title":"Laban Weight vs Time","x_label":"WeightAll (peak kinetic energy)",'
                  || '"y_label":"TimeAll (peak acceleration)","log_x":true,"log_y":true,"means":true}')
  FROM motion_laban;
SELECT '<h2>Emotion recognition: the sPCA embedding of the Fisher scores (thesis Fig. 4.5)</h2>'
    || '<p>One HMM per emotion; each training motion''s Fisher scores under the four HMMs, '
    || 'z-scored, projected by supervised PCA (RBF label kernel) onto its first two axes. Drawn '
    || 'by <code>laban_plot(json_extract(affect_scores(model, motion), ''$.embedding[0]''), …)</code>.</p>'
    || laban_plot(json_extract(s, '$.embedding[0]'), json_extract(s, '$.embedding[1]'), emotion,
                  '{"title":"Fisher scores, supervised PCA","x_label":"sPCA axis 1",'
                  || '"y_label":"sPCA axis 2","means":true}')
  FROM (SELECT d.emotion, affect_scores(c.model, d.motion) AS s
          FROM rec_data AS d, classifiers AS c);
SELECT '<h2>Salient joints: the heaviest sPCA weight of each HMM state''s covariance scores, by '
    || 'joint (thesis Fig. 4.6)</h2><p>Rows: emotion HMMs and their states (mixture 0); columns: '
    || 'the joints, in skeleton order; a cell is the largest weight among the state''s 32 heaviest '
    || 'covariance entries that name the joint (grey: none of them does). Darker is more '
    || 'discriminative. From <code>affect_salience(model, 32)</code>, drawn by '
    || '<code>affect_heatmap(row, column, value, options)</code>.</p>'
    || affect_heatmap(row, joint, w, '{"title":"Salient joints per HMM state","x_label":"joint",'
                                     || '"y_label":"emotion HMM, state","sort_rows":true}')
  FROM (SELECT a.label || ' · state ' || (a.state + 1) AS row, j.joint, j.k,
               max(json_extract(e.value, '$.weight')) AS w
          FROM affect_salience((SELECT model FROM classifiers), 32) AS a,
               json_each(a.top) AS e, json_each(e.value, '$.coordinates') AS c,
               (SELECT key AS k, value AS joint
                  FROM json_each(motion_info((SELECT posture FROM affect_salience(
                                                (SELECT model FROM classifiers)) LIMIT 1)),
                                 '$.names')) AS j
         -- a coordinate is "joint.axis", "v.joint.axis" for a velocity
         WHERE a.mixture = 0
           AND j.joint = substr(c.value, CASE WHEN c.value LIKE 'v.%' THEN 3 ELSE 1 END,
                                length(c.value) - 2 - CASE WHEN c.value LIKE 'v.%' THEN 2 ELSE 0 END)
         GROUP BY a.label, a.state, j.joint
         ORDER BY j.k, a.label, a.state);
SELECT '<h2>Key postures of the emotion HMMs</h2><p>A five-state HMM per emotion '
    || '(<code>hmm_train(motion, ''{"states":5,"covariance":"diag"}'')</code> on the recognizer''s '
    || 'training motions), '
    || 'each state''s mean posture from <code>hmm_postures(model)</code>, labelled by state: '
    || '<code>motion_svg(hmm_postures(model), ''{"labels":"state"}'')</code>.</p>'
    || group_concat('<figure>' || motion_svg(hmm_postures(model), json_object(
           'labels', 'state', 'size', 100, 'trajectories', json('false'), 'title', label))
       || '</figure>', '')
  FROM (SELECT emotion AS label, hmm_train(motion, '{"states":5,"covariance":"diag"}') AS model
          FROM rec_data GROUP BY emotion ORDER BY emotion);
SELECT '</body></html>';
.output stdout
SELECT 'wrote demo.html';
