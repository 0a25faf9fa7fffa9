"""The confusion matrix the diagnosis benchmarks print (blind/blind_diagnosis.py,
drift/drift_benchmark.py): one row per category of case, the cases it got right, how often each
effect was named, and how often the verdict was unexplained.

results: tuples (name, category, expected, named, unexplained, reduction_pct, seconds, correct).
"""


def confusion_table(results, names, first_header):
    categories = list(dict.fromkeys(r[1] for r in results))
    lines = [f"| {first_header} (cases) | correct | " + " | ".join(names) + " | unexplained |",
             "| --- | --- | " + " | ".join("---" for _ in names) + " | --- |"]
    for c in categories:
        rs = [r for r in results if r[1] == c]
        counts = [sum(1 for r in rs if n in r[3]) for n in names]
        lines.append(f"| {c} ({len(rs)}) | {sum(r[7] for r in rs)} | " + " | ".join(str(x) for x in counts) +
                     f" | {sum(1 for r in rs if r[4])} |")
    return "\n".join(lines)
