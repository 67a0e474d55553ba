"""Opens an HTML page in a real headless browser (Debian's chromium) and checks that every
image loads (naturalWidth > 0 after the load event) and every link resolves: a local file
must exist, an #anchor must name an id (or, in a Markdown file, a heading by GitHub's rule)
of its target. Links to other sites are listed, not fetched.

  /usr/bin/python3 -m tools.evidence.check_page docs/results/index.html [--browser chromium]

How: a copy of the page beside it (so relative paths resolve alike) gets a small script
that, on the load event, writes every image's URL and naturalWidth, every link's resolved
URL and the page's ids as JSON into the DOM; `chromium --headless --dump-dom` prints that
DOM. Exit 0 and "check_page: ok (N images, M links)", or 1 naming each broken image or link
(and 1 when the browser did not run the script)."""
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
from urllib.parse import unquote, urlparse

from tools.tests import docs_links
from tools.tttools import cli

SCRIPT = """<script>
window.addEventListener('load', function () {
  var r = {images: [], links: [], ids: []};
  Array.prototype.forEach.call(document.images, function (i) {
    r.images.push({src: i.src, raw: i.getAttribute('src'), w: i.naturalWidth});
  });
  Array.prototype.forEach.call(document.querySelectorAll('a[href]'), function (a) {
    r.links.push({href: a.href, raw: a.getAttribute('href')});
  });
  Array.prototype.forEach.call(document.querySelectorAll('[id]'), function (e) { r.ids.push(e.id); });
  var p = document.createElement('pre');
  p.id = 'tt-check-result';
  p.textContent = JSON.stringify(r);
  document.body.appendChild(p);
});
</script>"""


def html_ids(path):
    with open(path, encoding="utf-8", errors="replace") as f:
        text = f.read()
    return set(re.findall(r"""\b(?:id|name)\s*=\s*["']([^"']+)["']""", text))


def browse(page, browser, timeout):
    """The result dict the script wrote, from a copy of `page` opened in `browser`."""
    with open(page, encoding="utf-8") as f:
        text = f.read()
    if "</body>" in text:
        text = text.replace("</body>", SCRIPT + "</body>", 1)
    else:
        text += SCRIPT
    fd, copy = tempfile.mkstemp(prefix=".tt_check_page.", suffix=".html", dir=os.path.dirname(page))
    profile = tempfile.mkdtemp(prefix="tt_chromium.")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
        cmd = [browser, "--headless", "--disable-gpu", "--no-sandbox", "--no-first-run",
               "--allow-file-access-from-files", f"--user-data-dir={profile}",
               "--virtual-time-budget=15000", "--dump-dom", "file://" + os.path.abspath(copy)]
        try:
            p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               timeout=timeout)
        except FileNotFoundError:
            raise SystemExit(f"check_page: no browser {browser!r} (tools/bootstrap.sh installs chromium)")
        except subprocess.TimeoutExpired:
            raise SystemExit(f"check_page: {browser} did not finish in {timeout} s")
    finally:
        os.remove(copy)
        shutil.rmtree(profile, ignore_errors=True)
    m = re.search(r'<pre id="tt-check-result">(.*?)</pre>', p.stdout, re.S)
    if not m:
        raise SystemExit(f"check_page: {browser} did not run the check script on {page} (exit "
                         f"{p.returncode}): {p.stderr[-1500:]}")
    import html
    return json.loads(html.unescape(m.group(1))), copy


def check(page, browser="chromium", timeout=120):
    """A list of problems (empty: the page is fine) and the counts."""
    page = os.path.abspath(page)
    r, copy = browse(page, browser, timeout)
    problems = []
    for i in r["images"]:
        if not i["w"]:
            problems.append(f"image does not load: {i['raw']} ({i['src']})")
    ids = set(r["ids"])
    for a in r["links"]:
        u = urlparse(a["href"])
        if u.scheme in ("http", "https", "mailto"):
            continue
        if u.scheme != "file":
            problems.append(f"link with an unexpected scheme: {a['raw']}")
            continue
        path = unquote(u.path)
        if path == copy:
            path = page
        if not os.path.exists(path):
            problems.append(f"link to a missing file: {a['raw']} ({path})")
            continue
        if u.fragment:
            frag = unquote(u.fragment)
            if path == page:
                known = ids
            elif path.endswith((".html", ".htm")):
                known = html_ids(path)
            elif path.endswith(".md"):
                known = docs_links.anchors(path)
            else:
                known = set()
            if frag not in known:
                problems.append(f"link to a missing anchor: {a['raw']} (no #{frag} in {path})")
    if not r["images"]:
        problems.append("the page shows no image")
    return problems, len(r["images"]), len(r["links"])


def main(argv=None):
    ap = cli.parser(__doc__, host=False)
    ap.add_argument("page", help="the HTML file to check")
    ap.add_argument("--browser", default="chromium")
    ap.add_argument("--timeout", type=int, default=120, help="seconds the browser may take")
    a = ap.parse_args(argv)
    if not os.path.isfile(a.page):
        ap.exit(2, f"check_page: {a.page}: no such file\n")
    problems, ni, nl = check(a.page, a.browser, a.timeout)
    for p in problems:
        print(f"FAIL: {a.page}: {p}")
    if problems:
        return 1
    print(f"check_page: ok ({ni} images, {nl} links)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
