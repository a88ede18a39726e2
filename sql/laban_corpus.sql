-- laban_corpus.sql — Laban Effort and Shape by emotion over the real corpus: mean ± sd of
-- WeightAll, TimeAll, FlowAll and ShapeFlow for angry, happy, sad and normal, over the ten
-- contents recorded in every style (walk ×2, run, dash, walk-back, walk-left, walk-right, bow,
-- bye, byebye, guide: 11 motions per emotion), printed as a Markdown table, all contents and
-- then split into in-place gestures (bow, bye, byebye, guide) and locomotion (the other six,
-- whose Weight the walking or running speed dominates). Units follow the
-- corpus (cm, s): Weight cm²/s², Time cm/s², Flow cm/s³, Shape Flow cm³.
--
--   ./run.sh demo        # builds demo.db with the corpus, then:
--   sqlite3 demo.db -cmd '.load ./build/affect' < sql/laban_corpus.sql
.headers off
.mode list
WITH l AS (
    SELECT emotion, laban(motion) AS j,
           CASE WHEN content IN ('bow', 'bye', 'byebye', 'guide') THEN 'gestures' ELSE 'locomotion' END AS grp
      FROM motions
     WHERE source <> 'synth' AND emotion IN ('angry', 'happy', 'sad', 'normal')
       AND content IN ('walk', 'run', 'dash', 'walk-back', 'walk-left', 'walk-right',
                       'bow', 'bye', 'byebye', 'guide')
), v AS (
    SELECT emotion, grp, c.value AS component, json_extract(j, '$.' || c.value) AS x
      FROM l, json_each('["WeightAll","TimeAll","FlowAll","ShapeFlow"]') AS c
    UNION ALL
    SELECT emotion, 'all', c.value, json_extract(j, '$.' || c.value)
      FROM l, json_each('["WeightAll","TimeAll","FlowAll","ShapeFlow"]') AS c
), s AS (
    SELECT emotion, grp, component, count(*) AS n, avg(x) AS mean,
           sqrt(max(sum(x * x) - count(*) * avg(x) * avg(x), 0) / (count(*) - 1)) AS sd
      FROM v GROUP BY emotion, grp, component
), f AS (
    SELECT emotion, grp, component, n,
           CASE WHEN mean >= 1e5 THEN printf('%.3g', mean) ELSE printf('%.0f', mean) END || ' ± ' ||
           CASE WHEN sd >= 1e5 THEN printf('%.3g', sd) ELSE printf('%.0f', sd) END AS cell
      FROM s
)
SELECT '| contents | emotion | n | WeightAll (cm²/s²) | TimeAll (cm/s²) | FlowAll (cm/s³) | ShapeFlow (cm³) |'
UNION ALL SELECT '|---|---|---:|---:|---:|---:|---:|'
UNION ALL SELECT * FROM (
    SELECT printf('| %s | %s | %d | %s | %s | %s | %s |', grp, emotion, max(n),
                  max(CASE component WHEN 'WeightAll' THEN cell END),
                  max(CASE component WHEN 'TimeAll' THEN cell END),
                  max(CASE component WHEN 'FlowAll' THEN cell END),
                  max(CASE component WHEN 'ShapeFlow' THEN cell END))
      FROM f GROUP BY grp, emotion
     ORDER BY CASE grp WHEN 'all' THEN 0 WHEN 'gestures' THEN 1 ELSE 2 END,
              CASE emotion WHEN 'angry' THEN 0 WHEN 'happy' THEN 1 WHEN 'normal' THEN 2 ELSE 3 END);

-- the thesis's ordering, per content: is angry Stronger and more Sudden than sad?
SELECT '';
SELECT printf('angry > sad on WeightAll in %d of %d contents, on TimeAll in %d of %d; angry > normal > sad on both in %d of %d',
              sum(aw > sw), count(*), sum(at > st), count(*),
              sum(aw > nw AND nw > sw AND at > nt AND nt > st), count(*))
  FROM (
    SELECT a.name,
           laban_weight(a.motion) AS aw, laban_time(a.motion) AS at,
           laban_weight(n.motion) AS nw, laban_time(n.motion) AS nt,
           laban_weight(d.motion) AS sw, laban_time(d.motion) AS st
      FROM motions AS a
      JOIN motions AS n ON n.content = a.content AND n.emotion = 'normal' AND n.source = a.source
                        AND substr(n.name, -3) = substr(a.name, -3)
      JOIN motions AS d ON d.content = a.content AND d.emotion = 'sad' AND d.source = a.source
                        AND substr(d.name, -3) = substr(a.name, -3)
     WHERE a.emotion = 'angry' AND a.source <> 'synth');
