"""io/records: a missing key names its path; what is stored on a handed-out table stays."""

from __future__ import annotations

import pickle

import pytest
from pydantic import BaseModel, Field, ValidationError

from rotoprint.io.records import MissingKeyError, as_record, missing_key_message, validation_line


def test_a_missing_key_names_its_path_through_tables_and_lists():
    doc = as_record({"heads": [{"name": "A", "swathes": [{"clock": {}}, {}]}], "n": [1, 2]})
    with pytest.raises(MissingKeyError) as ei:
        doc["heads"][0]["swathes"][1]["clock"]
    assert (ei.value.where, ei.value.key) == ("heads[0].swathes[1]", "clock")
    assert missing_key_message(ei.value) == "heads[0].swathes[1] has no key 'clock': the program is incomplete"
    for h in doc["heads"]:  # iterating hands out the same wrapped tables as indexing
        for j, s in enumerate(h["swathes"]):
            with pytest.raises(MissingKeyError) as ei:
                s["nope"]
            assert ei.value.where == f"heads[0].swathes[{j}]"
    with pytest.raises(MissingKeyError) as ei:
        doc["missing"]
    assert missing_key_message(ei.value) == "the program has no key 'missing': the program is incomplete"
    assert type(doc["n"]) is list  # a list of numbers is handed back as it is
    assert isinstance(doc, dict) and doc.get("missing") is None  # .get and isinstance as a dict's


def test_what_is_stored_on_a_handed_out_table_stays_and_pickles():
    doc = as_record({"heads": [{"name": "A"}]})
    doc["heads"][0]["_model"] = 5
    assert doc["heads"][0]["_model"] == 5 and [h["_model"] for h in doc["heads"]] == [5]
    again = pickle.loads(pickle.dumps(doc))
    assert again == doc and again["heads"][0]["name"] == "A"


class _M(BaseModel):
    nozzles: int = Field(gt=0)
    kind: str = "x"


@pytest.mark.parametrize(("data", "line"), [
    ({"nozzles": "many"}, "field 'm.nozzles' must be a whole number, got 'many'"),
    ({"nozzles": 0}, "field 'm.nozzles' must be greater than 0, got 0"),
    ({}, "field 'm.nozzles' is missing (it is required)"),
    ({"nozzles": 1, "kind": 3}, "field 'm.kind' must be a text string, got 3"),
    ({"nozzles": "a", "kind": 3}, "field 'm.nozzles' must be a whole number, got 'a' (and 1 more problem(s))"),
])
def test_validation_errors_in_words(data, line):
    with pytest.raises(ValidationError) as ei:
        _M(**data)
    assert validation_line(ei.value, "m") == line
