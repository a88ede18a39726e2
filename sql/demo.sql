-- demo.sql — the demo's summary and its HTML page (run by `./run.sh demo` after the corpus
-- is built; see README). Prints what the database holds, then writes demo.html with SVG film
-- strips of the synthetic corpus and, when it was imported, of the real one.
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

-- ---- the HTML page ----
.headers off
.mode list
.output demo.html
SELECT '<!doctype html><html><head><meta charset="utf-8"><title>sqlite-affect demo</title>'
    || '<style>body{font-family:sans-serif;margin:2em;color:#222}h2{margin-top:2em}'
    || 'figure{display:inline-block;margin:0 1em 1em 0;vertical-align:top}'
    || 'figcaption{font-size:13px;color:#555}</style></head><body>'
    || '<h1>sqlite-affect demo</h1><p>Film strips drawn by <code>motion_svg(motion, options)</code>, '
    || 'straight from <code>demo.db</code>. Blue: left side, red: right side; faint lines: '
    || 'paths of the head, hands and feet.</p>';
SELECT '<h2>Synthetic corpus (motion_synth, performer seed 1)</h2>';
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
SELECT '<h2>Laban Weight and Time by emotion (thesis Fig. 5.1)</h2><p>Each point is a motion of the '
    || 'indexed source; crosses show each emotion''s mean ± 1 sd (log axes). Drawn by '
    || '<code>laban_plot(laban_weight(motion), laban_time(motion), emotion, …)</code>.</p>'
    || laban_plot(WeightAll, TimeAll, label,
                  '{"title":"Laban Weight vs Time","x_label":"WeightAll (peak kinetic energy)",'
                  || '"y_label":"TimeAll (peak acceleration)","log_x":true,"log_y":true,"means":true}')
  FROM motion_laban;
SELECT '</body></html>';
.output stdout
SELECT 'wrote demo.html';
