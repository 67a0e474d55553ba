"""The user docs agree with the tree: every relative link of every Markdown file in the
repository (README.md files, docs/) names a file that exists, and every #anchor names a
heading of its target, by GitHub's rule (lower case, punctuation dropped, spaces to '-',
repeats numbered -1, -2, ...), or an element id (id="..." / name="...") of an HTML target
such as the results page, docs/results/index.html. The checker first checks itself on a
made-up tree (a missing file, heading and HTML id found; good links not). Links into
../shared (the scenes beside the repository) and absolute URLs are not checked. Exit 1 naming each broken link with its file and line."""
import os
import re
import subprocess
import sys

ROOT = os.environ.get("TT_SOURCE_ROOT") or os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                        "..", "..")
LINK = re.compile(r"(?<!!)\[([^\]]*)\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
IMAGE = re.compile(r"!\[[^\]]*\]\(([^)\s]+)\)")


def markdown_files():
    try:
        out = subprocess.run(["git", "-C", ROOT, "ls-files", "*.md"], capture_output=True,
                             text=True, check=True).stdout.split()
    except (OSError, subprocess.CalledProcessError):  # not a git checkout: walk the tree
        out = []
        for d, subdirs, files in os.walk(ROOT):
            subdirs[:] = [s for s in subdirs if not s.startswith(".") and s not in
                          ("build", "subprojects")]
            out += [os.path.relpath(os.path.join(d, f), ROOT) for f in files if f.endswith(".md")]
    return sorted(f for f in out if not f.startswith("subprojects/"))


def slug(heading):
    """GitHub's anchor of a heading's text."""
    text = re.sub(r"`([^`]*)`", r"\1", heading.strip())
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", text)  # a link keeps its text
    text = re.sub(r"<[^>]+>", "", text).lower()
    text = re.sub(r"[^\w\- ]", "", text, flags=re.UNICODE)
    return text.replace(" ", "-")


_anchors = {}


def anchors(path):
    if path not in _anchors:
        seen, out, fence = {}, set(), False
        for line in open(path, encoding="utf-8"):
            if line.lstrip().startswith("```"):
                fence = not fence
            m = re.match(r"^(#{1,6})\s+(.*?)\s*#*\s*$", line)
            if m and not fence:
                s = slug(m.group(2))
                n = seen.get(s, 0)
                seen[s] = n + 1
                out.add(s if n == 0 else f"{s}-{n}")
            for a in re.findall(r"<a\s+(?:name|id)=\"([^\"]+)\"", line):
                out.add(a)
        _anchors[path] = out
    return _anchors[path]


_html_ids = {}


def html_ids(path):
    """The id and name attributes of an HTML file: what a #anchor into it can name."""
    if path not in _html_ids:
        text = open(path, encoding="utf-8", errors="replace").read()
        _html_ids[path] = set(re.findall(r"\s(?:id|name)=[\"']([^\"']+)[\"']", text))
    return _html_ids[path]


def broken_links(root, files):
    """Every broken relative link of the Markdown files `files` (paths relative to `root`)."""
    broken = []
    for rel in files:
        path = os.path.join(root, rel)
        fence = False
        for no, line in enumerate(open(path, encoding="utf-8"), 1):
            if line.lstrip().startswith("```"):
                fence = not fence
            if fence:
                continue
            line = re.sub(r"`[^`]*`", "", line)  # code spans are not links
            for target in [m.group(2) for m in LINK.finditer(line)] + IMAGE.findall(line):
                if re.match(r"^[a-z][a-z0-9+.-]*:", target) or target.startswith("//"):
                    continue  # http:, https:, mailto:
                file_part, _, anchor = target.partition("#")
                dest = os.path.normpath(os.path.join(os.path.dirname(path), file_part)) \
                    if file_part else path
                if os.path.relpath(dest, root).startswith(".."):
                    continue  # ../shared: beside the repository, not in it
                if not os.path.exists(dest):
                    broken.append(f"{rel}:{no}: {target}: no file {os.path.relpath(dest, root)}")
                    continue
                if anchor and dest.endswith(".md") and anchor not in anchors(dest):
                    broken.append(f"{rel}:{no}: {target}: {os.path.relpath(dest, root)} has no "
                                  f"heading #{anchor}")
                if anchor and dest.endswith((".html", ".htm")) and anchor not in html_ids(dest):
                    broken.append(f"{rel}:{no}: {target}: {os.path.relpath(dest, root)} has no "
                                  f"element with id #{anchor}")
    return broken


def self_check():
    """The checker itself finds what it must: in a made-up tree, a missing file, a missing
    heading and a missing HTML id are reported, and the good links of each kind are not.
    Returns the problems (empty when the checker works)."""
    import tempfile
    with tempfile.TemporaryDirectory() as d:
        with open(os.path.join(d, "page.html"), "w") as f:
            f.write('<h2><a id="here"></a>Here</h2><section id="there"></section>')
        with open(os.path.join(d, "b.md"), "w") as f:
            f.write("# A heading\n")
        with open(os.path.join(d, "a.md"), "w") as f:
            f.write("[ok](page.html#here) [ok](page.html#there) [ok](b.md#a-heading)\n"
                    "[bad](page.html#nowhere) [bad](b.md#nowhere) [bad](c.md)\n")
        got = broken_links(d, ["a.md", "b.md"])
    want = ["page.html#nowhere", "b.md#nowhere", "c.md"]
    problems = [f"not reported: {w}" for w in want if not any(f" {w}: " in g for g in got)]
    problems += [f"reported although good: {g}" for g in got if not any(f" {w}: " in g for w in want)]
    return problems


def main():
    problems = self_check()
    for p in problems:
        print("FAIL: the checker's self-check:", p)
    files = markdown_files()
    broken = broken_links(ROOT, files)
    for b in broken:
        print("FAIL:", b)
    print(f"docs_links: {len(files)} Markdown files, {len(broken)} broken links")
    return 1 if broken or problems or not files else 0


if __name__ == "__main__":
    sys.exit(main())
