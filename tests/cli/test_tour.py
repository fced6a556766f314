"""The ``terrawatt tour`` command (terrawatt_cli.tour): the files, the names in tour.json, nothing reachable, bad input."""

from __future__ import annotations

import json

from cli_samples import PNG_MAGIC

from terrawatt_cli import main


def _sites(tmp_path, rows):
    path = tmp_path / "sites.csv"
    path.write_text("name,x_m,y_m,value\n" + "".join(f"{r}\n" for r in rows))
    return path


def test_cli_plans_the_tours_and_writes_them(tmp_path, capsys, wall_map):
    tmap = wall_map.save(tmp_path / "wall.npz")
    sites = _sites(tmp_path, ["pump,5.5,35.5,2", "gate,30.5,31.5,1", "shed,35.5,5.5,1", "rock,20.5,10.5,3",
                              "away,90,90,1"])
    out = tmp_path / "out"
    rc = main(["tour", "--map", str(tmap), "--sites", str(sites), "--depot", "5.5", "5.5", "--battery-ah", "0.2",
               "--voltage", "24", "--robots", "2", "--risk", "0.9", "--out", str(out)])
    text = capsys.readouterr().out
    assert rc == 1, text  # two sites are error rows (as batch's rows); the others are planned and written
    doc = json.loads((out / "tour.json").read_text())
    assert doc["format"] == "terrawatt-tour" and doc["status"] == "planned" and len(doc["robots"]) == 2
    visited = [s for r in doc["robots"] for s in r["sites"]]
    assert set(visited) <= {"pump", "gate", "shed"} and visited
    assert {e["site"] for e in doc["errors"]} == {"away", "rock"}  # off the map; on the wall
    assert (out / "tour.png").read_bytes()[:8] == PNG_MAGIC and (out / "tour_soc.png").read_bytes()[:8] == PNG_MAGIC
    assert (out / "tour.geojson").is_file()
    assert "robot 1" in text and "wrote" in text


def test_cli_a_battery_that_reaches_nothing_exits_1_and_says_so(tmp_path, capsys, wall_map):
    tmap = wall_map.save(tmp_path / "wall.npz")
    sites = _sites(tmp_path, ["pump,5.5,35.5,2", "shed,35.5,5.5,1"])
    rc = main(["tour", "--map", str(tmap), "--sites", str(sites), "--depot", "5.5", "5.5", "--battery-ah", "0.0001",
               "--out", str(tmp_path / "out")])
    captured = capsys.readouterr()
    assert rc == 1 and "nothing reachable" in captured.out and "Traceback" not in captured.err


def test_cli_bad_sites_are_one_line_and_exit_2(tmp_path, capsys, wall_map):
    tmap = wall_map.save(tmp_path / "wall.npz")
    sites = _sites(tmp_path, ["pump,5.5,35.5,-2"])
    rc = main(["tour", "--map", str(tmap), "--sites", str(sites), "--depot", "5.5", "5.5", "--battery-ah", "1",
               "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert rc == 2 and "value must be >= 0" in err and err.count("\n") == 1
    rc = main(["tour", "--map", str(tmap), "--sites", str(sites), "--depot", "5.5", "5.5", "--battery-ah", "1",
               "--risk", "0.3", "--out", str(tmp_path / "out")])
    assert rc == 2 and "below the median" in capsys.readouterr().err


def test_cli_sites_all_on_the_map_exit_0(tmp_path, capsys, wall_map):
    tmap = wall_map.save(tmp_path / "wall.npz")
    sites = _sites(tmp_path, ["pump,5.5,35.5,2", "shed,35.5,5.5,1"])
    rc = main(["tour", "--map", str(tmap), "--sites", str(sites), "--depot", "5.5", "5.5", "--battery-ah", "0.2",
               "--voltage", "24", "--out", str(tmp_path / "out")])
    text = capsys.readouterr().out
    assert rc == 0, text
    assert json.loads((tmp_path / "out" / "tour.json").read_text())["errors"] == []


def test_cli_reads_time_windows_and_writes_the_arrival_times(tmp_path, capsys, wall_map):
    tmap = wall_map.save(tmp_path / "wall.npz")
    sites = tmp_path / "sites.csv"
    sites.write_text("name,x_m,y_m,value,service_time_s,tw_start_s,tw_end_s\n"
                     "pump,5.5,35.5,2,10,,\nshed,35.5,5.5,1,0,400,900\nshut,30.5,31.5,5,0,0,5\n")
    out = tmp_path / "out"
    rc = main(["tour", "--map", str(tmap), "--sites", str(sites), "--depot", "5.5", "5.5", "--battery-ah", "1",
               "--voltage", "24", "--out", str(out)])
    text = capsys.readouterr().out
    assert rc == 0, text
    doc = json.loads((out / "tour.json").read_text())
    robot = doc["robots"][0]
    assert set(robot["sites"]) == {"pump", "shed"} and doc["time_windows_s"] == {"shed": [400.0, 900.0],
                                                                                  "shut": [0.0, 5.0]}
    start = dict(zip(robot["sites"], robot["service_start_s"]))
    assert 400.0 <= start["shed"] <= 900.0 and len(robot["arrival_s"]) == 2 and robot["return_s"] > start["shed"]
    assert robot["service_time_s"] == [{"pump": 10.0, "shed": 0.0}[s] for s in robot["sites"]]
    assert [e["site"] for e in doc["left_out"]] == ["shut"] and "outside its time window" in text
    rc = main(["tour", "--map", str(tmap), "--sites", str(sites), "--depot", "5.5", "5.5", "--battery-ah", "1",
               "--voltage", "24", "--max-duration", "5000", "--out", str(tmp_path / "out2")])
    assert rc == 0 and "at most 5000 s" in capsys.readouterr().out
    assert json.loads((tmp_path / "out2" / "tour.json").read_text())["robots"][0]["max_duration_s"] == 5000.0
    rc = main(["tour", "--map", str(tmap), "--sites", str(sites), "--depot", "5.5", "5.5", "--battery-ah", "1",
               "--max-duration", "0", "--out", str(tmp_path / "out3")])
    assert rc == 2 and "--max-duration" in capsys.readouterr().err


def test_cli_a_bag_that_would_replace_an_input_is_refused_before_any_work(tmp_path, capsys, wall_map):
    out = tmp_path / "out"
    out.mkdir()
    tmap = wall_map.save(tmp_path / "wall.npz")
    sites = out / "tour_0.mcap"  # the sites file given as input sits where robot 0's bag would go
    sites.write_text("name,x_m,y_m,value\npump,5.5,35.5,2\n")
    before = sites.read_bytes()
    rc = main(["tour", "--map", str(tmap), "--sites", str(sites), "--depot", "5.5", "5.5", "--battery-ah", "0.2",
               "--voltage", "24", "--bag", "--out", str(out)])
    assert rc == 2 and "tour_0.mcap" in capsys.readouterr().err
    assert sites.read_bytes() == before and not (out / "tour.json").exists()


def test_cli_chargers_let_a_far_site_be_visited_and_tour_json_names_the_stops(tmp_path, capsys, wall_map):
    tmap = wall_map.save(tmp_path / "wall.npz")
    sites = _sites(tmp_path, ["pump,5.5,35.5,1", "shed,35.5,5.5,3"])  # dock -> shed -> dock with its U-turn: 0.12 Ah
    args = ["tour", "--map", str(tmap), "--sites", str(sites), "--depot", "5.5", "5.5", "--battery-ah", "0.13",
            "--voltage", "24", "--time-limit", "1"]
    rc = main(args + ["--out", str(tmp_path / "alone")])
    assert rc == 0 and "too far at Q: shed" in capsys.readouterr().out
    chargers = tmp_path / "chargers.csv"
    chargers.write_text("name,x_m,y_m,power_w,connection_time_s\ndock,20.5,32.5,80,10\n")
    out = tmp_path / "out"
    rc = main(args + ["--chargers", str(chargers), "--out", str(out)])
    text = capsys.readouterr().out
    assert rc == 0, text
    doc = json.loads((out / "tour.json").read_text())
    robot = doc["robots"][0]
    assert "shed" in robot["sites"] and "dock" in robot["stops"] and robot["charging_stops"]
    assert all(robot["stops"][k] == "dock" for k in robot["charging_stops"]) and "dock" in doc["chargers"]
    assert all(s["energy_at_risk_j"] <= s["budget_j"] for s in robot["segments"])
    assert "[charge dock]" in text
    chargers.write_text("name,x_m,y_m\ndock,20.5,95.5\n")
    rc = main(args + ["--chargers", str(chargers), "--out", str(tmp_path / "bad")])
    err = capsys.readouterr().err
    assert rc == 2 and "charger 'dock' is off the map" in err and err.count("\n") == 1


def test_cli_one_depot_per_robot(tmp_path, capsys, wall_map):
    tmap = wall_map.save(tmp_path / "wall.npz")
    sites = _sites(tmp_path, ["pump,5.5,35.5,1", "shed,35.5,5.5,1"])  # each robot's near site and back: 0.107 Ah
    args = ["tour", "--map", str(tmap), "--sites", str(sites), "--depot", "5.5", "5.5", "--depot", "35.5", "35.5",
            "--battery-ah", "0.12", "--voltage", "24"]
    rc = main(args + ["--out", str(tmp_path / "out")])
    text = capsys.readouterr().out
    assert rc == 0, text
    doc = json.loads((tmp_path / "out" / "tour.json").read_text())
    assert [r["depot_xy_m"] for r in doc["robots"]] == [[5.5, 5.5], [35.5, 35.5]]  # --robots defaults to 2
    assert "depot 1 ->" in text
    rc = main(args + ["--robots", "3", "--out", str(tmp_path / "bad")])
    err = capsys.readouterr().err
    assert rc == 2 and "--depot is given 2 times but --robots is 3" in err


def test_cli_monte_carlo_drives_the_tours_and_writes_tour_check_json(tmp_path, capsys, wall_map, monkeypatch):
    tmap = wall_map.save(tmp_path / "wall.npz")
    sites = _sites(tmp_path, ["pump,5.5,35.5,2", "shed,35.5,5.5,1"])
    out = tmp_path / "out"
    rc = main(["tour", "--map", str(tmap), "--sites", str(sites), "--depot", "5.5", "5.5", "--battery-ah", "0.2",
               "--voltage", "24", "--robots", "2", "--monte-carlo", "6", "--seed", "4", "--out", str(out)])
    text = capsys.readouterr().out
    assert rc == 0, text
    tours = json.loads((out / "tour.json").read_text())
    doc = json.loads((out / "tour_check.json").read_text())
    assert doc["format"] == "terrawatt-tour-check" and doc["format_version"] == 1 and doc["risk"] == 0.9
    driven = [r["robot"] for r in tours["robots"] if r["legs"]]
    assert [r["robot"] for r in doc["robots"]] == driven and driven
    assert all(r["n"] == 6 and r["stops"] == ["depot"] for r in doc["robots"])
    assert doc["draw_from"] == "parameters"  # the presets' exact price: the truth simulator draws
    assert (out / "tour_check.png").read_bytes()[:8] == PNG_MAGIC
    assert "each tour driven 6 times" in text and "above the reserve at Q = 0.9" in text and "tour_check.json" in text
    rc = main(["tour", "--map", str(tmap), "--sites", str(sites), "--depot", "5.5", "5.5", "--battery-ah", "0.2",
               "--monte-carlo", "0", "--out", str(tmp_path / "again")])
    err = capsys.readouterr().err
    assert rc == 2 and "--monte-carlo" in err and "an integer >= 1" in err and not (tmp_path / "again").exists()
    # a drive that fails is counted in tour_check.json and makes the exit code 1, as a Monte Carlo row with an error
    from planner.missions.monte_carlo import MissionSetup

    real = MissionSetup.run_chunk

    def dies_on_the_first_two(self, seqs):
        if any(q.spawn_key[0] < 2 for q in seqs):
            raise RuntimeError("worker lost")
        return real(self, seqs)

    monkeypatch.setattr(MissionSetup, "run_chunk", dies_on_the_first_two)
    rc = main(["tour", "--map", str(tmap), "--sites", str(sites), "--depot", "5.5", "5.5", "--battery-ah", "0.2",
               "--voltage", "24", "--monte-carlo", "6", "--out", str(tmp_path / "failed")])
    text = capsys.readouterr().out
    doc = json.loads((tmp_path / "failed" / "tour_check.json").read_text())
    assert rc == 1 and doc["n_failed"] >= 2 and f"{doc['n_failed']} tours failed" in text


def test_cli_monte_carlo_draws_as_asked(tmp_path, capsys, wall_map, monkeypatch):
    import planner.tours.check as check_module

    tmap = wall_map.save(tmp_path / "wall.npz")
    sites = _sites(tmp_path, ["pump,5.5,35.5,2"])
    seen = []
    real = check_module.simulate_missions_mc

    def spy(terrain, route, battery, study, **kw):
        seen.append(study)
        return real(terrain, route, battery, study, **kw)

    monkeypatch.setattr(check_module, "simulate_missions_mc", spy)
    base = ["tour", "--map", str(tmap), "--sites", str(sites), "--depot", "5.5", "5.5", "--battery-ah", "0.2",
            "--voltage", "24"]
    rc = main([*base, "--monte-carlo", "4", "--mc-priced-load", "--out", str(tmp_path / "priced")])
    capsys.readouterr()
    assert rc == 0 and seen and all(s.draw_from == "parameters" for s in seen)
    assert all(s.distributions.payload_kg == (0.0, 0.0) and s.distributions.capacity_fade_pct == (0.0, 0.0)
               for s in seen)
    assert seen[0].distributions.ground_coef_scale == (0.8, 1.2)  # the other draws as by default
    for extra, words in ((["--mc-priced-load"], "apply to --monte-carlo"),
                         (["--monte-carlo", "4", "--mc-priced-load", "--mc-draw", "model"], "give one")):
        rc = main([*base, *extra, "--out", str(tmp_path / "refused")])
        err = capsys.readouterr().err
        assert rc == 2 and words in err and not (tmp_path / "refused").exists()


def test_cli_no_improve_reports_the_solvers_tours(tmp_path, capsys, wall_map, monkeypatch):
    """``--no-improve`` is ``TourSearch(improve=False)``: the step does not run, tour.json says it added nothing and
    the summary has no line for it; without the flag the step runs."""
    import terrawatt_cli.tour as tour_command

    tmap = wall_map.save(tmp_path / "wall.npz")
    sites = _sites(tmp_path, ["pump,5.5,35.5,2", "gate,30.5,31.5,1", "shed,35.5,5.5,1"])
    seen = []
    real = tour_command.plan_tour_on_map

    def spy(*args, search, **kw):
        seen.append(search.improve)
        return real(*args, search=search, **kw)

    monkeypatch.setattr(tour_command, "plan_tour_on_map", spy)
    base = ["tour", "--map", str(tmap), "--sites", str(sites), "--depot", "5.5", "5.5", "--battery-ah", "0.2",
            "--voltage", "24"]
    assert main([*base, "--no-improve", "--out", str(tmp_path / "plain")]) == 0
    text = capsys.readouterr().out
    doc = json.loads((tmp_path / "plain" / "tour.json").read_text())
    assert doc["format_version"] == 4 and (doc["sites_added"], doc["sites_swapped"], doc["improve_time_s"]) == (0, 0, 0)
    assert "improvement step" not in text
    assert main([*base, "--out", str(tmp_path / "improved")]) == 0
    capsys.readouterr()
    assert seen == [False, True]
