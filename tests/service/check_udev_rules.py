#!/usr/bin/env python3
"""59-handtrack-cameras.rules: the three OpenNI2 camera vendors get group handtrack, mode 0660,
never world-writable, with final (":=") assignments in a file that sorts before any installed
rules file that would otherwise make them world-writable (Debian's 60-libopenni2-0.rules).
Also a small evaluator of the rules for typical devices: a camera gets handtrack/0660, a
Microsoft keyboard or any other USB device is left alone.

    check_udev_rules.py RULES_FILE
"""
import os
import re
import sys

RULE_DIRS = ["/etc/udev/rules.d", "/run/udev/rules.d", "/usr/lib/udev/rules.d", "/lib/udev/rules.d",
             "/usr/local/lib/udev/rules.d"]
VENDORS = {"1d27", "2bc5", "045e"}
failures = []


def fail(message):
    failures.append(message)
    print("FAIL:", message)


def parse(path):
    """Rules as lists of (key, op, value)."""
    rules = []
    for line in open(path, encoding="utf-8"):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        pairs = re.findall(r'([A-Z]+(?:\{[^}]*\})?)\s*(==|!=|:=|\+=|-=|=)\s*"([^"]*)"', line)
        if not pairs:
            fail(f"{path}: cannot parse '{line}'")
        rules.append(pairs)
    return rules


def glob_match(pattern, value):
    return any(re.fullmatch(alt.replace("*", ".*").replace("?", "."), value) for alt in pattern.split("|"))


def evaluate(rules, device):
    """Applies the rules to a device dict (keys like SUBSYSTEM, ATTR{idVendor}); returns the
    GROUP/MODE assignments, honouring GOTO/LABEL and ':=' finality."""
    result, final, i = {}, set(), 0
    labels = {pairs[0][2]: n for n, pairs in enumerate(rules) if pairs[0][0] == "LABEL"}
    while i < len(rules):
        pairs, matched, goto = rules[i], True, None
        for key, op, value in pairs:
            if op in ("==", "!="):
                ok = glob_match(value, device.get(key, ""))
                if (op == "==") != ok:
                    matched = False
                    break
        if matched:
            for key, op, value in pairs:
                if key in ("GROUP", "MODE", "OWNER") and op in ("=", ":=") and key not in final:
                    result[key] = value
                    if op == ":=":
                        final.add(key)
                elif key == "GOTO":
                    goto = value
        i = labels[goto] if goto else i + 1
    return result


path = sys.argv[1]
name = os.path.basename(path)
rules = parse(path)

for pairs in rules:
    for key, op, value in pairs:
        if key == "MODE":
            if op != ":=" or value != "0660":
                fail(f"MODE must be ':=\"0660\"', not '{op}\"{value}\"'")
            if int(value, 8) & 0o007:
                fail(f"mode {value} gives others access")
        if key == "GROUP" and (op != ":=" or value != "handtrack"):
            fail(f"GROUP must be ':=\"handtrack\"', not '{op}\"{value}\"'")
vendors = {v for pairs in rules for k, _, v in pairs if k == "ATTR{idVendor}"}
if vendors != VENDORS:
    fail(f"vendors {sorted(vendors)}, expected {sorted(VENDORS)}")

usb = {"ACTION": "add", "SUBSYSTEM": "usb", "ENV{DEVTYPE}": "usb_device"}
cases = [
    ("Asus Xtion PRO LIVE", {"ATTR{idVendor}": "1d27", "ATTR{idProduct}": "0601"}, True),
    ("PrimeSense Carmine", {"ATTR{idVendor}": "1d27", "ATTR{idProduct}": "0600"}, True),
    ("Orbbec Astra", {"ATTR{idVendor}": "2bc5", "ATTR{idProduct}": "0401"}, True),
    ("Kinect for Xbox 360 camera", {"ATTR{idVendor}": "045e", "ATTR{idProduct}": "02ae"}, True),
    ("Kinect for Windows camera", {"ATTR{idVendor}": "045e", "ATTR{idProduct}": "02bf"}, True),
    ("Microsoft keyboard", {"ATTR{idVendor}": "045e", "ATTR{idProduct}": "07f8"}, False),
    ("Logitech webcam", {"ATTR{idVendor}": "046d", "ATTR{idProduct}": "0825"}, False),
]
for label, attrs, expected in cases:
    got = evaluate(rules, {**usb, **attrs})
    wanted = {"GROUP": "handtrack", "MODE": "0660", "OWNER": "root"} if expected else {}
    if got != wanted:
        fail(f"{label}: {got}, expected {wanted}")
    # A USB interface of the same camera (not the device node libusb opens) is left alone.
    if evaluate(rules, {**usb, **attrs, "ENV{DEVTYPE}": "usb_interface"}):
        fail(f"{label}: rules apply to usb_interface events")
    if evaluate(rules, {**usb, **attrs, "ACTION": "remove"}):
        fail(f"{label}: rules apply to remove events")

# Order against the rules installed on this machine: any file assigning a final MODE or GROUP to
# one of our vendors must sort after ours (ours is final first), and 50-udev-default.rules'
# plain MODE="0664" for USB devices must come before ours (it does: 50 < 59).
for directory in RULE_DIRS:
    if not os.path.isdir(directory):
        continue
    for other in sorted(os.listdir(directory)):
        if other == name or not other.endswith(".rules"):
            continue
        text = open(os.path.join(directory, other), encoding="utf-8", errors="replace").read()
        for line in text.splitlines():
            if line.lstrip().startswith("#"):
                continue
            if re.search(r'(MODE|GROUP):=', line) and any(f'"{v}"' in line for v in VENDORS):
                if other < name:
                    fail(f"{directory}/{other} sorts before {name} and finalizes: {line.strip()}")
                else:
                    print(f"ok: {directory}/{other} comes after {name} (its ':=' cannot override ours)")
                break
if not (name.split("-", 1)[0] > "50"):
    fail(f"{name} must sort after 50-udev-default.rules")

print("udev rules ok" if not failures else f"{len(failures)} failure(s)")
sys.exit(1 if failures else 0)
