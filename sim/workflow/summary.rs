//! The workflow's one page: per task, the finalists ranked (reach-only numbers, what fine-tuning
//! did, the full validation's verdict and goals), the best designs' pictures, links to each
//! design's HTML report. Self-contained but for those files, beside it in the workflow's folder.

use super::TaskOutcome;

fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn link(path: &std::path::Path) -> String {
    escape(&path.to_string_lossy().replace('\\', "/"))
}

/// The summary page of a workflow's tasks.
pub fn summary_html(outcomes: &[TaskOutcome]) -> String {
    let mut page = String::from(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>proving-ground workflow</title>\n<style>\n\
         body { font-family: sans-serif; margin: 2em; color: #222; }\n\
         table { border-collapse: collapse; margin: 1em 0; }\n\
         th, td { border: 1px solid #ccc; padding: 0.3em 0.6em; text-align: left; vertical-align: top; }\n\
         th { background: #f2f2f2; }\n\
         .PASS { color: #0a0; font-weight: bold; } .FAIL { color: #c00; font-weight: bold; } .UNDECIDED { color: #c70; font-weight: bold; }\n\
         figure { display: inline-block; margin: 0.5em; } img { max-width: 420px; border: 1px solid #ddd; }\n\
         </style>\n</head>\n<body>\n<h1>proving-ground workflow</h1>\n",
    );
    page.push_str("<p>Per task: candidates, the reach-only filter (ranked tasks solved first, then goals solved, then the paper's task loss), fine-tuning of the best (a result that loses ground on its original is not kept), and the full validation of each: the verdict is the design's, FAIL only for what is proven.</p>\n");
    for outcome in outcomes {
        page.push_str(&format!(
            "<h2 id=\"{id}\">Task {name}</h2>\n<p>{count} candidates: {source}; {finalists} finalists; {seconds:.1} s.</p>\n",
            id = escape(&outcome.scenario),
            name = escape(&outcome.scenario),
            count = outcome.candidates,
            source = escape(&outcome.source),
            finalists = outcome.finalists.len(),
            seconds = outcome.seconds,
        ));
        page.push_str("<table>\n<tr><th>rank</th><th>candidate</th><th>reach-only: goals solved</th><th>task loss</th><th>fine-tuning</th><th>validated design</th><th>verdict</th><th>reached / unreachable / undecided / no path</th><th>report</th></tr>\n");
        for f in &outcome.finalists {
            let count = |outcome: &str| f.report.goals.iter().filter(|g| g.outcome == outcome).count();
            let loss = f.reach.task_loss.map_or_else(|| "-".to_string(), |l| format!("{l:.3}"));
            page.push_str(&format!(
                "<tr><td>{rank}</td><td>{candidate}</td><td>{solved}/{goals}</td><td>{loss}</td><td>{refined}</td><td>{design}</td><td class=\"{word}\">{word}</td><td>{reached} / {unreachable} / {undecided} / {no_path}</td><td><a href=\"{report}\">report</a></td></tr>\n",
                rank = f.rank,
                candidate = escape(&f.candidate),
                solved = f.reach.goals_solved,
                goals = f.reach.goals,
                refined = escape(&f.refined),
                design = f.design_file.as_ref().and_then(|p| p.file_name()).map_or_else(|| escape(&f.candidate), |n| format!("<a href=\"{}\">{}</a>", link(&f.report_html.with_file_name(n)), escape(&n.to_string_lossy()))),
                word = f.report.verdict.word,
                reached = count("reached"),
                unreachable = count("unreachable"),
                undecided = count("undecided"),
                no_path = count("no_path"),
                report = link(&f.report_html),
            ));
        }
        page.push_str("</table>\n");
        for f in &outcome.finalists {
            page.push_str(&format!(
                "<figure><a href=\"{report}\"><img src=\"{picture}\" alt=\"{candidate} in the task's scene\"></a><figcaption>{rank}. {candidate}: <span class=\"{word}\">{word}</span></figcaption></figure>\n",
                report = link(&f.report_html),
                picture = link(&f.picture),
                candidate = escape(&f.candidate),
                rank = f.rank,
                word = f.report.verdict.word,
            ));
        }
    }
    // The title says whether every picture loaded (`ok N of N pictures`), for a browser check.
    page.push_str(
        "<script>\nwindow.addEventListener('load', () => {\n  const images = Array.from(document.images);\n  const loaded = images.filter((i) => i.complete && i.naturalWidth > 0).length;\n  document.title = (loaded === images.length ? 'ok ' : 'error: ') + loaded + ' of ' + images.length + ' pictures';\n});\n</script>\n",
    );
    page.push_str("</body>\n</html>\n");
    page
}
