"""The report's generated sentences are checks that can come out false: each is
computed from the numbers it describes, here on the numbers of the report that once printed "the
distance falls as δ decreases on every level" over a table where it rose."""
import os

HERE = os.path.dirname(os.path.abspath(__file__))

from sdcompare_lib import sentences

# mixed's report: broken/M1star, distance to dolfinx per level and δ
MIXED = {
    0: [(1.0, 0.1142), (1e-2, 0.1198), (1e-4, 0.1246), (0.0, 0.1247)],
    1: [(1.0, 0.0610), (1e-2, 0.0410), (1e-4, 0.0390), (0.0, 0.0389)],
    4: [(1.0, 0.01873), (1e-2, 0.003751), (0.0, 0.003955)],
}


def test_a_distance_that_rises_on_some_levels_is_said_to_rise_there():
    text = sentences.delta_trend(MIXED)
    assert text == ("the distance falls as δ decreases on level 1 only; on level 0 it rises from "
                    "0.1142 at δ = 1 to 0.1198 at δ = 1e-2; on level 4 it rises from 0.003751 at "
                    "δ = 1e-2 to 0.003955 at δ = 0")
    assert "every level" not in text


def test_a_distance_that_falls_everywhere_is_said_to_fall_on_every_level():
    falling = {lv: pts for lv, pts in MIXED.items() if lv == 1}
    falling[2] = [(0.0, 0.01), (1.0, 0.02)]  # given in any order: sorted by δ
    assert sentences.delta_trend(falling) == "the distance falls as δ decreases on every level"


def test_a_distance_that_rises_everywhere_is_said_to_fall_nowhere():
    text = sentences.delta_trend({0: MIXED[0], 4: MIXED[4]})
    assert text.startswith("the distance does not fall as δ decreases on any level: on level 0")


def test_equal_distances_do_not_count_as_a_rise():
    assert sentences.delta_trend({3: [(1e-2, 0.5), (0.0, 0.5)]}).endswith("on every level")


def test_the_floor_sentence_follows_the_floors():
    assert sentences.floor_trend([0.1, 0.05, 0.02]) == "the floor decreases with h (0.1 → 0.05 → 0.02)"
    assert sentences.floor_trend([0.1, 0.12]).startswith("**the floor does not decrease with h**")
    assert sentences.floor_trend([0.1, None]) == "no δ = 0 floor on every level"
