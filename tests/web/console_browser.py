#!/usr/bin/env python3
"""The console page in headless Chromium against a running robocald + robocal-cellsim
(console_test.sh starts them and a run). Each check prints a line; the first failure exits 1."""
import argparse
import html
import json
import subprocess
import sys
import time
import urllib.request

from prometheus_client.parser import text_string_to_metric_families
from selenium import webdriver
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.common.by import By


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--web-port", type=int, required=True)
    ap.add_argument("--tcp-port", type=int, required=True)
    ap.add_argument("--token-file", required=True)
    ap.add_argument("--cellsim", required=True)
    ap.add_argument("--robocal", required=True)
    ap.add_argument("--screenshot", required=True)
    a = ap.parse_args()
    base = f"http://127.0.0.1:{a.web_port}"
    token = open(a.token_file).read().strip()

    options = webdriver.ChromeOptions()
    options.binary_location = "/usr/bin/chromium"
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--window-size=1400,1100",
                "--disable-dev-shm-usage"):
        options.add_argument(arg)
    driver = webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=options)
    try:
        run(driver, a, base, token)
    finally:
        driver.quit()


def check(ok, what):
    print(("ok    " if ok else "FAIL  ") + what, flush=True)
    if not ok:
        sys.exit(1)


def wait_until(what, predicate, timeout_s=30.0):
    deadline = time.monotonic() + timeout_s
    value = None
    while time.monotonic() < deadline:
        try:
            value = predicate()
        except Exception:  # an element not there yet
            value = None
        if value:
            return value
        time.sleep(0.1)
    check(False, what + f" (within {timeout_s:.0f} s)")


def text(driver, element_id):
    return driver.find_element(By.ID, element_id).text


def points_done(driver):
    return int(text(driver, "points").split("/")[0])


def metrics(base):
    body = urllib.request.urlopen(base + "/metrics", timeout=10).read().decode()
    samples = {}
    for family in text_string_to_metric_families(body):
        for s in family.samples:
            key = s.name + "".join(f"{{{k}={v}}}" for k, v in sorted(s.labels.items()))
            samples[key] = s.value
    return samples


def shots(driver, path, what):
    """Screenshots at 1280 and 800 px wide beside `path` (console.png -> console-WHAT-1280.png),
    then back to the test's own size."""
    stem = path[:-4] if path.endswith(".png") else path
    for width in (1280, 800):
        driver.set_window_size(width, 1000)
        time.sleep(0.6)  # a few frames at the new size
        driver.save_screenshot(f"{stem}-{what}-{width}.png")
    driver.set_window_size(1400, 1100)
    check(True, f"screenshots of the {what} at 1280 and 800 px: {stem}-{what}-*.png")


def robocal(a, *args):
    return subprocess.run([a.robocal, *args], capture_output=True, text=True, timeout=60).stdout


def run(driver, a, base, token):
    driver.get(base + "/")
    check("robocal console" in driver.title, "the page loads: " + driver.title)
    wait_until("the WebSocket is live", lambda: text(driver, "link") == "live")
    check(text(driver, "release").startswith("robocald "), "VERSION shown: " + text(driver, "release"))

    # The trace moves: the bar streams readings, the count and the value change.
    first = wait_until("bar readings arrive", lambda: int(text(driver, "bar-count")) > 0 and
                       int(text(driver, "bar-count")))
    time.sleep(1.0)
    check(int(text(driver, "bar-count")) > first + 10,
          f"the trace moves: {first} -> {text(driver, 'bar-count')} readings in 1 s")
    trace_pixels = driver.execute_script(
        "const c = document.getElementById('trace');"
        "const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;"
        "let n = 0; for (let i = 0; i < d.length; i += 4)"
        "  if (d[i] === 31 && d[i + 1] === 119 && d[i + 2] === 180) ++n; return n;")
    check(trace_pixels > 50, f"the trace is drawn ({trace_pixels} pixels of its colour)")

    # A prompt appears.
    message = wait_until("a connect prompt appears",
                         lambda: "Connect" in text(driver, "prompt-message") and
                         text(driver, "prompt-message"))
    check(text(driver, "state") == "Waiting for the operator", "the state in words: " + message)
    check(driver.find_element(By.ID, "confirm").is_enabled(), "Confirm is enabled")
    # What the prompt is about, in the run panel too (it read "shell 0 of 9" and no connection).
    wait_until("the run id is shown", lambda: text(driver, "run") not in ("", "–"))
    check(text(driver, "shell").startswith("1 of "), "the prompt's shell: " + text(driver, "shell"))
    check(text(driver, "connection").startswith("B"), "its connection: " + text(driver, "connection"))
    check(driver.find_element(By.ID, "pause").is_enabled(), "Pause is enabled while a run goes")
    check(not driver.find_element(By.ID, "resume").is_enabled(), "Resume is not: nothing to resume")
    shots(driver, a.screenshot, "prompt")

    # Confirm without the token is refused; the run stays where it is.
    driver.find_element(By.ID, "confirm").click()
    refusal = wait_until("the refusal is shown", lambda: "token" in text(driver, "last-reply") and
                         text(driver, "last-reply"))
    check("error" in driver.find_element(By.ID, "last-reply").get_attribute("class"),
          "Confirm without the token is refused: " + refusal)
    time.sleep(0.5)
    check(text(driver, "state") == "Waiting for the operator", "the run still waits for the operator")
    m = metrics(base)
    check(m.get("robocal_run_state{state=awaiting_confirm}") == 1.0,
          "/metrics parses (prometheus_client) and says awaiting_confirm")
    check(m.get("robocal_clients{transport=web}", 0) >= 1, "/metrics counts the browser")

    # The operator's hands: the bar goes onto the chuck in the simulated cell.
    prompt_words = message.split()
    ball, chuck = prompt_words[2], prompt_words[5]  # "Connect ball 1 to chuck 1 ..."
    reply = robocal(a, "cellsim", a.cellsim, f"connect B{ball}C{chuck} extension_mm=0 bar_mm=150")
    check(reply.startswith("ok"), "the simulated bar is connected: " + reply.strip())

    # The token typed once into the page; Confirm with it goes on.
    driver.find_element(By.ID, "token").send_keys(token)
    driver.find_element(By.ID, "token-save").click()
    check(text(driver, "token-state").startswith("token set for this tab"), "the token is kept for the tab")
    check(token not in driver.current_url, "the token is not in the URL")
    check(driver.find_element(By.ID, "token").get_attribute("value") == "",
          "the token field is emptied once used")
    driver.find_element(By.ID, "confirm").click()
    wait_until("the confirm is acknowledged", lambda: "confirm:" in text(driver, "last-reply") and
               "error" not in driver.find_element(By.ID, "last-reply").get_attribute("class"))
    check(True, "Confirm with the token is acknowledged: " + text(driver, "last-reply"))

    # The progress advances.
    done = wait_until("points are measured", lambda: points_done(driver) >= 3 and points_done(driver),
                      timeout_s=60)
    check(done >= 3, "the progress advances: " + text(driver, "points"))
    check(driver.find_element(By.ID, "progress").get_attribute("value") not in ("0", None),
          "the progress bar moved")
    wait_until("the next prompt (detach after shell 1)",
               lambda: "Detach" in text(driver, "prompt-message"), timeout_s=60)
    time.sleep(0.5)  # a few frames of the trace
    driver.save_screenshot(a.screenshot)
    check(True, "screenshot mid-run: " + a.screenshot)
    m = metrics(base)
    check(m.get("robocal_samples_total", 0) >= 3, f"/metrics counts samples: {m.get('robocal_samples_total')}")
    check(m.get("robocal_points_done", 0) == points_done(driver), "/metrics and the page agree on points done")

    # Paused: loud, in the operator panel, with what gets the run going.
    driver.find_element(By.ID, "pause").click()
    wait_until("the run pauses", lambda: text(driver, "state") == "PAUSED", timeout_s=30)
    panel = driver.find_element(By.ID, "prompt")
    check("stopped" in panel.get_attribute("class"), "the operator panel turns to the pause")
    check("paused at the console" in text(driver, "prompt-message") and
          not text(driver, "prompt-message").startswith("PAUSED: paused"),
          "it says why: " + text(driver, "prompt-message"))
    check("Resume" in text(driver, "prompt-action"), "and what to do: " + text(driver, "prompt-action"))
    check(driver.find_element(By.ID, "resume").is_enabled(), "Resume is enabled when paused")
    check(not driver.find_element(By.ID, "pause").is_enabled(), "Pause is not")
    shots(driver, a.screenshot, "paused")

    # Abort: two presses, the second ends the run.
    driver.find_element(By.ID, "abort").click()
    check("again" in text(driver, "last-reply"), "Abort asks for a second press")
    driver.find_element(By.ID, "abort").click()
    wait_until("the run is aborted", lambda: text(driver, "state") == "Aborted", timeout_s=30)
    check(True, "Abort from the page ends the run")
    wait_until("the run history shows it", lambda: "aborted" in text(driver, "runs"))
    check(True, "the run history lists the aborted run")
    check(not driver.find_element(By.ID, "abort").is_enabled(), "Abort is disabled: nothing to end")
    shots(driver, a.screenshot, "ended")

    # A run to its end, the simulated operator at the bar: the fit's verdict on the result card
    # is RESULT's, word for word as `robocal result` and the run's summary.html give it. Two
    # shells of 8 points cannot calibrate: the card must say NOT USABLE, why, and what next.
    watcher = subprocess.Popen([a.robocal, "watch", "--port", str(a.tcp_port), "--operator-cellsim",
                                a.cellsim, "--until", "done,paused,aborted,error", "--timeout-s",
                                "200"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    time.sleep(0.5)  # watching before the run starts: no prompt is missed
    started = subprocess.run([a.robocal, "start", "--port", str(a.tcp_port)], capture_output=True,
                             text=True, timeout=60)
    check(started.returncode == 0, "a second run starts: " + started.stdout.strip())
    watched = watcher.communicate(timeout=240)[0]
    check(watcher.returncode == 0, "the run ends done (robocal watch exits 0 only then): " +
          " | ".join(watched.splitlines()[-2:]))
    box = wait_until("the result card shows a verdict",
                     lambda: driver.find_element(By.ID, "verdict"), timeout_s=60)
    result = json.loads(robocal(a, "result", "--port", str(a.tcp_port), "--json"))
    verdict = result["verdict"]
    check(not verdict["usable"] and "bad" in box.get_attribute("class"),
          "the card says NOT USABLE, as RESULT does: " + box.text.splitlines()[0])
    check(all(p in box.text for p in verdict["problems"]) and len(verdict["problems"]) > 0,
          f"the card lists RESULT's {len(verdict['problems'])} problem(s)")
    check(verdict["model_file"] in box.text and verdict["next"]["command"] in box.text,
          "and its model path and next command: " + verdict["next"]["command"])
    printed = robocal(a, "result", "--port", str(a.tcp_port))
    for line in box.text.splitlines()[:1] + ["next: " + verdict["next"]["command"]]:
        check(line in printed, "robocal result prints the same: " + line)
    page = open(result["report_dir"] + "/summary.html").read()
    check(html.escape(verdict["problems"][0], quote=True).replace("&#x27;", "&#39;") in page and
          "NOT USABLE as a calibration" in page, "summary.html gives the same verdict")
    driver.execute_script("document.getElementById('result').scrollIntoView()")
    shots(driver, a.screenshot, "result")


if __name__ == "__main__":
    main()
