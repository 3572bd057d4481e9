#!/usr/bin/env python3
"""A model of visvol-build-mpi at theatre scale, from costs measured here.

Each rank builds a band of every level's rows (whole 16-row bricks), the
scatter and the terrain force field of its own rows, and writes its tiles.
Split by observers (visvol-build-mpi's default), it computes the hulls of its
band's observers only and sends the int32 partial sums of the rows within range
beside its band to the ranks that own them; split by rows (--split rows), the
hulls of the observers within range around its band too (the halo, computed
again by its neighbours). Rank 0 imports the DEM and broadcasts it. The
slowest rank (an interior one, with the most bricks) sets the time.

    tools/bench/mpi_build_model.py --measured HULL_S SCATTER_S TFF_S [options]

The costs come from a 1-rank, 1-thread visvol-build-mpi run (its rank line:
hull s, scatter s, tff s, all levels) of a calibration grid, by default the
512 x 512 Taunus DEM with three levels of detail at range 64
(tools/bench/README.md): hull and scatter per interior observer (the
calibration grid's observers near its edges have part of their range outside
it, so each level's observers are counted by the share of their range inside),
the terrain force field per post.
"""
import argparse
import math


def clipped_share(n, r):
    """Mean share of an observer's (2r+1)^2 range square inside an n x n grid."""
    width = sum(min(x, r) + min(n - 1 - x, r) + 1 for x in range(n)) / n
    return (width / (2 * r + 1)) ** 2


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--posts", type=int, default=20000, help="posts a side of level 0 (default 20000)")
    p.add_argument("--lod", type=int, default=4, help="levels of detail (default 4)")
    p.add_argument("--range", type=int, default=64, help="range in posts, every level (default 64)")
    p.add_argument("--nz", type=int, default=128, help="voxel levels (default 128)")
    p.add_argument("--measured", type=float, nargs=3, required=True, metavar=("HULL_S", "SCATTER_S", "TFF_S"),
                   help="a 1-rank 1-thread run's hull, scatter and terrain force field seconds, all levels")
    p.add_argument("--calibration-posts", type=int, default=512, help="posts a side of the calibration grid")
    p.add_argument("--calibration-lod", type=int, default=3, help="its levels of detail")
    p.add_argument("--write-mib-s", type=float, default=500.0, help="a rank's write rate to the shared file system")
    p.add_argument("--link-gib-s", type=float, default=10.0,
                   help="network bandwidth a rank (the terrain's broadcast, the observer split's partial sums)")
    p.add_argument("--threads", type=int, default=1, help="cores a rank (default 1)")
    p.add_argument("--ranks", type=int, nargs="+", default=[16, 64, 256])
    p.add_argument("--split", choices=["rows", "observers"], default="observers",
                   help="observers (the default): each hull once, the partial sums of the 2 x range rows beside a "
                        "band sent to the ranks that own them; rows: each rank computing the hulls of its halo "
                        "again")
    a = p.parse_args()

    # the calibration run's work in interior observers (hull, scatter) and posts (terrain force field)
    levels = [math.ceil(a.calibration_posts / 2 ** l) for l in range(a.calibration_lod)]
    interior = sum(n * n * clipped_share(n, a.range) for n in levels)
    posts = sum(n * n for n in levels)
    hull_us = a.measured[0] / interior * 1e6
    scatter_us = a.measured[1] / interior * 1e6
    tff_us = a.measured[2] / posts * 1e6
    bytes_per_post = a.nz * 2 + 24 * 4 * 2 + 8  # uint16 F_p, 24-sample terrain force band, height and area

    def rank_time(ranks):
        hull = scatter = tff = write = exchange = 0.0
        for level in range(a.lod):
            n = math.ceil(a.posts / 2 ** level)
            bricks = math.ceil(n / 16)
            rows = min(n, 16 * math.ceil(bricks / ranks))  # the busiest rank's rows
            halo = 2 * a.range if ranks > 1 and a.split == "rows" else 0
            observers_rows = min(n, rows + halo)
            hull += observers_rows * n * hull_us
            if ranks > 1 and a.split == "observers":  # int32 partial sums of (nz + 1) levels, both sides
                exchange += 2 * min(n, a.range) * n * (a.nz + 1) * 4 / (a.link_gib_s * 2 ** 30)
            scatter += rows * n * scatter_us
            tff += rows * n * tff_us
            write += rows * n * bytes_per_post
        cores = a.threads
        broadcast = 0.0 if ranks == 1 else a.posts ** 2 * 4 * math.ceil(math.log2(ranks)) / (a.link_gib_s * 2 ** 30)
        return {
            "hull": hull / cores / 1e6,
            "scatter": scatter / cores / 1e6,
            "tff": tff / cores / 1e6,
            "write": write / (a.write_mib_s * 2 ** 20),
            "broadcast": broadcast + exchange,
        }

    serial = sum(rank_time(1).values())
    print(f"split by {a.split}: {a.posts} x {a.posts} x {a.nz} posts, {a.lod} levels of detail, range {a.range} posts, "
          f"{a.threads} core(s) a rank; interior hull {hull_us:.1f} us an observer, scatter {scatter_us:.1f} us, "
          f"terrain force field {tff_us:.1f} us a post; write {a.write_mib_s:.0f} MiB/s a rank, "
          f"broadcast {a.link_gib_s:.0f} GiB/s")
    print(f"one rank: {serial / 3600:.1f} h")
    # a rank's terrain: its plan's levels of detail, the builder's copy padded by the range and the per-post
    # observer weights (rank 0 also keeps the imported DEM)
    terrain_gib = sum(math.ceil(a.posts / 2 ** l) ** 2 for l in range(a.lod)) * 4
    terrain_gib = (terrain_gib + (a.posts + 2 * a.range) ** 2 * 4 + a.posts ** 2 * 4) / 2 ** 30
    print("ranks  hull s  scatter s  tff s  write s  exchange s  wall     efficiency  terrain a rank")
    for ranks in a.ranks:
        t = rank_time(ranks)
        wall = sum(t.values())
        print(f"{ranks:5d}  {t['hull']:6.0f}  {t['scatter']:9.0f}  {t['tff']:5.0f}  {t['write']:7.0f}  "
              f"{t['broadcast']:10.1f}  {wall / 60:5.1f} min  {serial / (ranks * wall):10.2f}  "
              f"{terrain_gib:.1f} GiB")


if __name__ == "__main__":
    main()
