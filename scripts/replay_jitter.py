#!/usr/bin/env python3
"""Real-time replay jitter of the tracker, from a bag recorded by scripts/demo.

The tracker stamps the k-th /torque message with its nominal time start + t_k / rate_factor and
publishes it when the wall clock reaches that time. rosbag record stores the time each message
arrived. So, per message:
  lateness  = arrival − header stamp              (publication + transport delay)
  period    = arrival_k − arrival_{k−1}            (against the nominal stamp_k − stamp_{k−1})
Usage: /usr/bin/python3 scripts/replay_jitter.py BAG [--topic /torque]
"""
import argparse
import statistics

import rosbag


def percentile(values, q):
    s = sorted(values)
    return s[min(len(s) - 1, int(round(q * (len(s) - 1))))]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("bag")
    ap.add_argument("--topic", default="/torque")
    args = ap.parse_args()
    stamps, arrivals = [], []
    with rosbag.Bag(args.bag) as bag:
        for _, msg, t in bag.read_messages(topics=[args.topic]):
            stamps.append(msg.header.stamp.to_sec())
            arrivals.append(t.to_sec())
    if len(stamps) < 3:
        raise SystemExit("fewer than 3 messages on %s" % args.topic)
    late = [1e3 * (a - s) for a, s in zip(arrivals, stamps)]
    err = [1e3 * ((arrivals[k] - arrivals[k - 1]) - (stamps[k] - stamps[k - 1]))
           for k in range(1, len(stamps))]
    nominal = 1e3 * statistics.median(stamps[k] - stamps[k - 1] for k in range(1, len(stamps)))
    print("messages on %s: %d, nominal period %.3f ms" % (args.topic, len(stamps), nominal))
    print("lateness (arrival - stamp) [ms]: median %.3f, p95 %.3f, max %.3f, min %.3f" %
          (statistics.median(late), percentile(late, 0.95), max(late), min(late)))
    absd = [abs(e) for e in err]
    print("period error (arrival delta - stamp delta) [ms]: median |.| %.3f, p95 |.| %.3f, "
          "max |.| %.3f, std %.3f" % (statistics.median(absd), percentile(absd, 0.95), max(absd),
                                      statistics.pstdev(err)))


if __name__ == "__main__":
    main()
