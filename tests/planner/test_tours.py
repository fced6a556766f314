"""Tours on one charge (planner.tours): the exhaustive optimum, uphill != downhill, bad input, the outputs, the Monte Carlo check."""

from __future__ import annotations

import dataclasses
import itertools
import json

import numpy as np
import pytest

from energy import Battery
from planner import EnergyCost, Lattice
from planner.tours import (TourProblem, TourRobot, TourSites, plan_tour, price_pairs, read_tour_sites_csv,
                           simulate_tours_mc)
from planner.tours.solver import solve_pyvrp
from planner.tours.tour import NOT_WORTH_IT, TOO_FAR
from terrain import DataError, InvalidParameterError, TerrainMap, flat_map
from terrain.georef import xy_to_lonlat


def _with_interval(cost: EnergyCost, rel_sd: float = 0.15) -> EnergyCost:
    """``cost`` with a run-level spread of ``rel_sd`` of every mean entry (one ground's spreads shared by the run)."""
    sd = np.nan_to_num(np.abs(rel_sd * cost.grade_table_j_per_m), nan=0.0, posinf=0.0)
    return cost.with_tables(cost.grade_table_j_per_m, cost.turn_table_j, ground_labels=cost.ground_labels,
                            grade_sd_table_j_per_m=sd, turn_sd_table_j=np.abs(rel_sd * cost.turn_table_j))


def _hills_map() -> TerrainMap:
    """40 x 40 cells of 1 m: two round hills on asphalt, sand on the east half (two grounds)."""
    y, x = np.mgrid[0:40, 0:40] + 0.5
    z = 3.0 * np.exp(-((x - 14) ** 2 + (y - 26) ** 2) / 60.0) + 2.0 * np.exp(-((x - 28) ** 2 + (y - 12) ** 2) / 40.0)
    ground = np.where(x > 20, 1, 0)
    return TerrainMap(z, 1.0, ground=ground, ground_names={0: "asphalt", 1: "sand"})


@pytest.fixture(scope="module")
def hills_cost() -> EnergyCost:
    return _with_interval(EnergyCost.from_presets(_hills_map()))


def _exhaustive(problem: TourProblem) -> float:
    """The best value over every assignment of the candidates to the robots and every order (1 or 2 robots)."""
    sites = problem.site_points.tolist()
    value = dict(zip(sites, problem.prize.tolist()))
    best = 0
    n_robots = len(problem.depot_points)
    for k in range(len(sites) + 1):
        for seq in itertools.permutations(sites, k):
            splits = [(seq,)] if n_robots == 1 else [(seq[:i], seq[i:]) for i in range(k + 1)]
            for tours in splits:
                if all(problem.tour_units(r, t) <= problem.capacity_units[r] for r, t in enumerate(tours)):
                    best = max(best, sum(value[s] for s in seq))
    return best


def _problem(cost: EnergyCost, sites: TourSites, robots: list[TourRobot], q: float) -> TourProblem:
    """The integer problem plan_tour solves, built from the same pricing (one depot)."""
    depot = robots[0].depot_xy_m
    pts = np.vstack([depot, sites.xy_m])
    prices = price_pairs(cost, pts, ("depot", *sites.names), risk=q)
    value = np.concatenate([[0.0], sites.value])
    return TourProblem.build(prices, q, [r.budget_j for r in robots], [0] * len(robots),
                             np.arange(1, len(pts)), value, np.concatenate([[0.0], sites.service_energy_j]))


@pytest.mark.parametrize("n_sites, n_robots, q, ah", [(8, 1, 0.9, 0.12), (8, 1, 0.5, 0.12), (6, 2, 0.9, 0.06)])
def test_the_tours_value_equals_the_exhaustive_optimum(hills_cost, n_sites, n_robots, q, ah):
    rng = np.random.default_rng(n_sites + n_robots)
    xy = rng.uniform(3.0, 37.0, size=(n_sites, 2))
    sites = TourSites(tuple(f"s{k}" for k in range(n_sites)), xy, value=rng.integers(1, 6, n_sites).astype(float))
    robots = [TourRobot(Battery(ah, 24.0, min_reserve_pct=20.0), (20.0, 20.0), f"r{k}") for k in range(n_robots)]
    res = plan_tour(hills_cost, sites, robots, risk=q, seed=1)
    best = _exhaustive(_problem(hills_cost, sites, robots, q))
    assert res.status == "planned"
    assert 0 < res.value < sites.value.sum()  # the battery binds: a real choice
    assert round(res.value * 100) * (int(_problem(hills_cost, sites, robots, q).capacity_units.sum()) + 1) == best
    for tour in res.tours:  # every tour holds at its own quantile
        assert tour.energy.quantile_j(q) <= tour.budget_j
        assert tour.arrival_soc_at_risk >= tour.battery.reserve_soc - 1e-12
    assert set(res.visited) | set(res.left_out) == set(sites.names)


def test_a_higher_risk_level_visits_no_more():
    cost = _with_interval(EnergyCost.from_presets(_hills_map()), rel_sd=0.3)
    rng = np.random.default_rng(3)
    sites = TourSites(tuple(f"s{k}" for k in range(7)), rng.uniform(3.0, 37.0, size=(7, 2)))
    robot = TourRobot(Battery(0.1, 24.0), (20.0, 20.0))
    values = [plan_tour(cost, sites, robot, risk=q).value for q in (0.5, 0.9, 0.99)]
    assert values[0] >= values[1] >= values[2] and values[0] > values[2]


def test_paths_from_one_search_equals_the_pairwise_optimum(hills_cost):
    lat = Lattice.for_cost(hills_cost)
    goals = np.array([[5.0, 5.0], [35.5, 30.2], [14.0, 26.0], [30.0, 3.0]])
    for path, goal in zip(lat.paths_from((20.0, 20.0), goals), goals):
        assert path.objective == pytest.approx(lat.shortest_path((20.0, 20.0), tuple(goal)).objective, rel=1e-12)


def _ridge_map() -> TerrainMap:
    """40 x 40 cells of 1 m of snow: a north-south ridge (y >= 10) whose west face (grade 0.25) snow cannot climb
    but can descend, and whose east face is gentle (grade 0.075); flat south of y = 10."""
    y, x = np.mgrid[0:40, 0:40] + 0.5
    prof = np.where(x < 12, 0.0, np.where(x < 18, 0.25 * (x - 12), np.maximum(1.5 - 0.075 * (x - 18), 0.0)))
    return TerrainMap(np.where(y >= 10, prof, 0.0), 1.0, ground=np.zeros((40, 40), int), ground_names={0: "snow"})


def test_uphill_and_downhill_priced_apart_choose_the_cheaper_direction():
    """Over a ridge a loop costs another energy each way round; a symmetric cost prices both the same, so it
    cannot prefer the cheap direction and, with a tight battery, believes the loop does not fit."""
    cost = EnergyCost.from_presets(_ridge_map())
    sites = TourSites(("west", "east"), [[4.5, 36.5], [36.5, 36.5]])
    depot = (4.5, 4.5)
    prices = price_pairs(cost, np.vstack([depot, sites.xy_m]), ("depot", *sites.names))
    assert prices.mean_j[1, 2] > 1.3 * prices.mean_j[2, 1]  # west -> east goes round the ridge, east -> west over it
    cheap, dear = prices.tour_interval([0, 2, 1, 0]).mean_j, prices.tour_interval([0, 1, 2, 0]).mean_j
    assert dear > 1.1 * cheap
    res = plan_tour(cost, sites, TourRobot(Battery(5.0, 24.0), depot))
    assert res.tours[0].sites == ("east", "west") and res.tours[0].energy.mean_j == pytest.approx(cheap)
    symmetric = dataclasses.replace(prices, mean_j=(prices.mean_j + prices.mean_j.T) / 2)
    sym_loop = symmetric.tour_interval([0, 1, 2, 0]).mean_j
    assert sym_loop == pytest.approx(symmetric.tour_interval([0, 2, 1, 0]).mean_j) == pytest.approx((cheap + dear) / 2)
    # a battery between the cheap direction and the symmetric price: both sites, against one by the symmetric cost
    budget_j = (cheap + sym_loop) / 2
    battery = Battery(budget_j / (0.8 * 24.0 * 3600.0), 24.0, min_reserve_pct=20.0)
    tight = plan_tour(cost, sites, TourRobot(battery, depot))
    sym_tours = solve_pyvrp(TourProblem.build(symmetric, 0.9, [budget_j], [0], [1, 2], [0.0, 1.0, 1.0], [0.0] * 3))
    assert tight.value == 2 and len(sym_tours[0]) == 1
    assert tight.tours[0].energy.mean_j <= budget_j


def test_a_site_off_the_map_or_on_an_obstacle_is_an_error_row_and_the_others_are_kept():
    obstacle = np.zeros((30, 30), bool)
    obstacle[10:14, 10:14] = True
    tmap = TerrainMap(np.zeros((30, 30)), 1.0, ground=np.zeros((30, 30), int), ground_names={0: "asphalt"},
                      obstacle=obstacle)
    cost = EnergyCost.from_presets(tmap)
    sites = TourSites(("ok", "off", "rock", "ok2"), [[5.0, 5.0], [45.0, 5.0], [11.5, 11.5], [20.0, 25.0]])
    res = plan_tour(cost, sites, TourRobot(Battery(1.0, 24.0), (2.0, 2.0)))
    assert set(res.errors) == {"off", "rock"}
    assert "off the map" in res.errors["off"] and "obstacle" in res.errors["rock"]
    assert set(res.visited) == {"ok", "ok2"}
    doc = res.to_dict()
    assert {e["site"] for e in doc["errors"]} == {"off", "rock"}


def test_bad_sites_raise_the_librarys_errors(tmp_path):
    with pytest.raises(InvalidParameterError, match="unique; 'a' appears 2 times"):
        TourSites(("a", "a"), [[1.0, 1.0], [2.0, 2.0]])
    with pytest.raises(InvalidParameterError, match="value must be >= 0 for every site; site 1 has -2.0"):
        TourSites(("a", "b"), [[1.0, 1.0], [2.0, 2.0]], value=[1.0, -2.0])
    with pytest.raises(InvalidParameterError, match="xy_m"):
        TourSites(("a",), [[np.nan, 1.0]])
    csv = tmp_path / "sites.csv"
    csv.write_text("name,x_m,y_m,value\na,1,1,1\na,2,2,1\n")
    with pytest.raises(DataError, match="used twice"):
        read_tour_sites_csv(csv)
    csv.write_text("name,x_m,y_m,value\na,1,1,-1\n")
    with pytest.raises(InvalidParameterError, match="value must be >= 0"):
        read_tour_sites_csv(csv)
    csv.write_text("name,x_m,y_m,value\na,1,1,lots\n")
    with pytest.raises(DataError, match="line 2: column 'value' is 'lots'"):
        read_tour_sites_csv(csv)
    cost = EnergyCost.from_presets(flat_map((20, 20), 1.0))
    with pytest.raises(InvalidParameterError, match="risk 0.2 lies below the median"):
        plan_tour(cost, TourSites(("a",), [[5.0, 5.0]]), TourRobot(Battery(1.0, 24.0), (2.0, 2.0)), risk=0.2)
    twins = [TourRobot(Battery(1.0, 24.0), (2.0, 2.0), "r")] * 2
    with pytest.raises(InvalidParameterError, match="robot names must be unique; 'r' appears 2 times"):
        plan_tour(cost, TourSites(("a",), [[5.0, 5.0]]), twins)
    with pytest.raises(InvalidParameterError, match="needs? .*georeferenced|CRS"):
        TourSites.from_lonlat(("a",), [[10.0, 46.0]], flat_map((20, 20), 1.0))


def test_sites_in_degrees_are_placed_by_the_maps_crs(tmp_path):
    pytest.importorskip("rasterio", reason="degrees need the geo extra (rasterio's transforms)")
    tmap = flat_map((20, 20), 10.0, origin_xy_m=(500000.0, 5100000.0))
    tmap.crs = "EPSG:32632"
    xy = np.array([[500055.0, 5100045.0], [500120.0, 5100150.0]])
    lon, lat = xy_to_lonlat(xy[:, 0], xy[:, 1], tmap.crs)
    sites = TourSites.from_lonlat(("a", "b"), np.column_stack([lon, lat]), tmap, value=[1.0, 2.0])
    assert np.allclose(sites.xy_m, xy, atol=1e-3)
    csv = tmp_path / "sites.csv"
    csv.write_text("name,lon,lat,value\n" + "".join(f"{n},{x!r},{y!r},{v}\n" for n, x, y, v in
                                                     zip("ab", lon.tolist(), lat.tolist(), (1, 2))))
    read = read_tour_sites_csv(csv, tmap)
    assert read.names == ("a", "b") and np.allclose(read.xy_m, xy, atol=1e-3) and read.value.tolist() == [1.0, 2.0]


def test_sites_all_worth_nothing_are_a_plan_without_tours():
    cost = EnergyCost.from_presets(flat_map((20, 20), 1.0))
    res = plan_tour(cost, TourSites(("a",), [[5.0, 5.0]], value=[0.0]), TourRobot(Battery(1.0, 24.0), (2.0, 2.0)))
    assert res.status == "planned" and res.visited == () and res.left_out == {"a": NOT_WORTH_IT}


def test_a_battery_that_reaches_no_site_answers_nothing_reachable():
    cost = EnergyCost.from_presets(flat_map((40, 40), 1.0))
    sites = TourSites(("a", "b"), [[30.0, 30.0], [35.0, 5.0]])
    res = plan_tour(cost, sites, TourRobot(Battery(0.001, 24.0), (2.0, 2.0)))
    assert res.status == "nothing reachable" and res.value == 0
    assert res.left_out == {"a": TOO_FAR, "b": TOO_FAR}
    assert "nothing reachable" in res.summary()


def test_the_result_writes_json_geojson_and_figures_and_names_the_left_out(tmp_path, hills_cost):
    sites = TourSites(("a", "b", "c", "zero"), [[10.0, 10.0], [30.0, 30.0], [12.0, 30.0], [20.0, 22.0]],
                      value=[3.0, 1.0, 2.0, 0.0], service_energy_j=[100.0, 0.0, 0.0, 0.0])
    res = plan_tour(hills_cost, sites, TourRobot(Battery(0.1, 24.0), (20.0, 20.0)))
    files = {p.name for p in res.write(tmp_path)}
    assert files == {"tour.json", "tour.geojson", "tour.png", "tour_soc.png"}
    doc = json.loads((tmp_path / "tour.json").read_text())
    assert doc["format"] == "terrawatt-tour" and doc["format_version"] == 1
    robot = doc["robots"][0]
    assert robot["sites"] == list(res.tours[0].sites) and res.left_out["zero"] == NOT_WORTH_IT
    assert len(robot["legs"]) == len(robot["sites"]) + 1
    soc = robot["soc"]
    assert soc["band_low"][-1] <= soc["mean"][-1] <= soc["band_high"][-1]
    assert soc["at_risk"][-1] >= 0.2 - 1e-12
    assert np.all(np.diff(soc["mean"]) < 0)
    spent = res.tours[0].energy.mean_j
    legs = sum(leg["energy_j"] for leg in robot["legs"])
    assert spent == pytest.approx(legs + (100.0 if "a" in robot["sites"] else 0.0))
    geo = json.loads((tmp_path / "tour.geojson").read_text())
    assert len(geo["features"]) == len(robot["legs"])
    assert "robot 0" in res.summary()


def test_monte_carlo_of_the_tours_ends_above_the_reserve_about_as_often_as_q(hills_cost):
    rng = np.random.default_rng(5)
    sites = TourSites(tuple(f"s{k}" for k in range(12)), rng.uniform(3.0, 37.0, size=(12, 2)))
    robot = TourRobot(Battery(0.15, 24.0), (20.0, 20.0))
    shares = {}
    for q in (0.5, 0.9):
        res = plan_tour(hills_cost, sites, robot, risk=q)
        check = simulate_tours_mc(res, 400, seed=2)
        shares[q] = check.share_above_reserve
        assert check.draw_from == "model" and "above the reserve" in check.summary()
    assert shares[0.9] >= 0.88
    assert shares[0.5] < shares[0.9] - 0.1  # the knob means something


def test_each_robots_tour_is_written_as_a_ros2_bag(tmp_path, hills_cost):
    pytest.importorskip("rosbags", reason="the ROS 2 output needs the ros extra")
    from planner.ros_export import read_route_bag

    sites = TourSites(("a", "b"), [[10.0, 10.0], [30.0, 30.0]])
    res = plan_tour(hills_cost, sites, TourRobot(Battery(0.2, 24.0), (20.0, 20.0)))
    written = res.write(tmp_path, bag=True)
    assert tmp_path / "tour_0.mcap" in written
    bag = read_route_bag(tmp_path / "tour_0.mcap")
    assert np.allclose(bag.waypoints_m[0], (20.0, 20.0)) and np.allclose(bag.waypoints_m[-1], (20.0, 20.0))
