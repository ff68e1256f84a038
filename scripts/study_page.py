"""What every study script that writes a results page does alike: the load average it records in
the page's header, and the page written to --out (or printed)."""


def load_average():
    """The 1, 5 and 15 minute load averages, as the header of a page records them."""
    with open("/proc/loadavg") as f:
        return " ".join(f.read().split()[:3])


def write_page(page, out):
    """Writes `page` to the file `out`, or prints it where `out` is empty."""
    if out:
        with open(out, "w") as f:
            f.write(page)
    else:
        print(page)
