"""The plant's pure parts: addresses as typed, config tables, payloads and numbers."""

from __future__ import annotations

import json

import pytest

from rac_console.commands.language import VarRef
from rac_console.commands.plant import (
    Credentials,
    Publish,
    parse_metrics_address,
    parse_mqtt_address,
    parse_publish,
    topic_level,
)
from rac_console.commands.profiles import parse_config
from rac_console.engine.polling.plant_tap import plant_name
from rac_console.plant.payload import numeric_fields, payload, value_json
from rac_console.protocol import KINDS, VT, InputError, Variant
from rac_console.protocol.variables import R4_ARRAY


def var(code: str, index: int) -> VarRef:
    return VarRef(KINDS[code], index)


@pytest.mark.parametrize(
    ("text", "host", "port", "prefix", "tls"),
    [
        ("mqtt://broker.plant/line2", "broker.plant", 1883, "line2", False),
        ("mqtt://10.0.0.5:1884/plant/line2/", "10.0.0.5", 1884, "plant/line2", False),
        ("mqtts://broker/line2", "broker", 8883, "line2", True),
        ("MQTT://[::1]:1883/p", "::1", 1883, "p", False),
    ],
)
def test_a_broker_address_as_typed(text: str, host: str, port: int, prefix: str, tls: bool) -> None:
    address = parse_mqtt_address(text)
    assert (address.host, address.port, address.prefix, address.tls) == (host, port, prefix, tls)
    assert parse_mqtt_address(str(address)) == address


@pytest.mark.parametrize(
    ("text", "says"),
    [
        ("broker/line2", "give the broker as mqtt://"),
        ("tcp://broker/line2", "starts with mqtt:// or mqtts://"),
        ("mqtt://user:pa55word@broker/line2", "no user or password"),
        ("mqtt://user@broker/line2", "no user or password"),
        # A base64 password holds / (and ? or #): what precedes the @ is no host.
        ("mqtt://rac:4711/s3cret@127.0.0.1:1883/line2", "no user or password"),
        ("mqtt://rac:47?11@broker/line2", "no user or password"),
        ("mqtt://rac:47#11@broker/line2", "no user or password"),
        ("mqtts://rac:s3/cr/et@broker:8883/line2", "no user or password"),
        ("mqtt://broker", "give a topic prefix"),
        ("mqtt://broker:70000/p", "port"),
        ("mqtt://broker:0/p", "port"),
        ("mqtt:///p", "names no host"),
        ("mqtt://broker/a//b", "empty level"),
        ("mqtt://broker/a/#", "reserve"),
        ("mqtt://broker/a+b", "reserve"),
        ("mqtt://broker/p?x=1", "no ? or # part"),
        ("mqtt://broker#x/p", "no ? or # part"),
        ("mqtt://a..b/p", "not a name or address"),
        ("mqtt://broker/$SYS/x", "the broker's own"),
        ("mqtt://broker//p", "empty level"),
    ],
)
def test_a_broker_address_that_cannot_be_used_says_how_to_write_it(text: str, says: str) -> None:
    with pytest.raises(InputError) as refused:
        parse_mqtt_address(text)
    assert says in str(refused.value)
    for secret in ("pa55word", "s3cret", "4711", "47", "cr/et"):
        assert secret not in str(refused.value)


def test_a_topic_level_keeps_out_wildcards_separators_and_control_characters() -> None:
    assert topic_level("cell3", "the target") == "cell3"
    assert topic_level("10.0.0.5:5007", "the target") == "10.0.0.5:5007"
    for bad in ("a/b", "a+", "#", "", "a\x00b", "a\x1bb"):
        with pytest.raises(InputError):
            topic_level(bad, "the target")


@pytest.mark.parametrize(
    ("text", "host", "port", "loopback"),
    [
        ("9108", "127.0.0.1", 9108, True),
        ("0", "127.0.0.1", 0, True),
        ("127.0.0.1:9108", "127.0.0.1", 9108, True),
        ("[::1]:9108", "::1", 9108, True),
        ("localhost:9108", "localhost", 9108, True),
        ("0.0.0.0:9108", "0.0.0.0", 9108, False),
        ("10.0.0.9:9108", "10.0.0.9", 9108, False),
    ],
)
def test_metrics_are_served_on_loopback_unless_another_address_is_written(
    text: str, host: str, port: int, loopback: bool
) -> None:
    address = parse_metrics_address(text)
    assert (address.host, address.port, address.loopback) == (host, port, loopback)


@pytest.mark.parametrize("text", ["", "nine", "127.0.0.1:", ":9108x", "65536", "a b:1"])
def test_a_metrics_address_that_cannot_be_one_is_refused(text: str) -> None:
    with pytest.raises(InputError, match=r"--metrics takes \[HOST:\]PORT"):
        parse_metrics_address(text)


def test_publish_as_typed() -> None:
    assert parse_publish("") == Publish(None)
    assert parse_publish("off") == Publish(None, off=True)
    assert parse_publish("mqtt://b/p") == Publish(parse_mqtt_address("mqtt://b/p"))
    with pytest.raises(InputError, match="one address"):
        parse_publish("mqtt://b/p mqtt://c/p")


def test_credentials_never_show_their_password() -> None:
    shown = repr(Credentials("rac", "s3cret", None))
    assert "s3cret" not in shown and "rac" in shown


# ------------------------------------------------------------------ the config file


def test_the_config_names_a_broker_per_profile_and_per_cell_and_who_we_are_to_it() -> None:
    parsed = parse_config(
        {
            "target": {
                "cell3": {"host": "10.0.0.3", "publish": "mqtt://broker/line2"},
                "cell4": {"host": "10.0.0.4"},
            },
            "cell": {"line2": {"targets": ["cell3", "cell4"], "publish": "mqtts://broker/l2"}},
            "mqtt": {"username": "rac", "password": "pw", "ca_file": "/etc/ca.pem"},
        },
        "config.toml",
    )
    assert parsed.profiles["cell3"].publish == "mqtt://broker:1883/line2"
    assert parsed.profiles["cell4"].publish is None
    assert parsed.cells["line2"].publish == "mqtts://broker:8883/l2"
    assert parsed.mqtt == Credentials("rac", "pw", "/etc/ca.pem")


@pytest.mark.parametrize(
    ("data", "says"),
    [
        ({"mqtt": {"user": "rac"}}, "[mqtt] unknown key 'user': use username, password"),
        ({"mqtt": {"password": 1234}}, '[mqtt] password: write password = "..."'),
        ({"mqtt": "rac"}, "[mqtt] is a table"),
        (
            {"target": {"c": {"host": "h", "publish": "mqtt://broker"}}},
            "[target.c] publish: give a topic prefix",
        ),
        (
            {"target": {"c": {"host": "h"}}, "cell": {"l": {"targets": ["c"], "publish": 5}}},
            "[cell.l] publish: write publish",
        ),
    ],
)
def test_a_config_problem_with_the_plant_is_one_line_naming_the_key(
    data: dict[str, object], says: str
) -> None:
    with pytest.raises(InputError) as refused:
        parse_config(data, "config.toml")
    assert str(refused.value).startswith("config.toml: ")
    assert says in str(refused.value)
    assert "1234" not in str(refused.value)  # a password is not repeated


# ------------------------------------------------------------------ payloads and numbers


def test_a_payload_carries_the_value_as_json_gives_it_with_fields_by_name() -> None:
    position = Variant(R4_ARRAY, [350.0, 0.0, 450.0, 180.0, 0.0, 180.0, 5.0])
    data = json.loads(payload("cell3", var("P", 1), "home", position, "OK", 0.25))
    assert data == {
        "value": {
            "X": 350.0,
            "Y": 0.0,
            "Z": 450.0,
            "Rx": 180.0,
            "Ry": 0.0,
            "Rz": 180.0,
            "Fig": 5.0,
        },
        "vartype": "VT_R4|VT_ARRAY",
        "status": "OK",
        "time": "1970-01-01T00:00:00.250Z",
        "target": "cell3",
        "variable": "P1",
        "label": "home",
    }
    assert value_json(var("IO", 128), Variant(VT.BOOL, True)) is True
    assert value_json(var("I", 1), Variant(VT.I4, 7)) == 7


def test_a_failed_read_is_published_with_no_value_not_the_stale_one() -> None:
    data = json.loads(payload("cell3", var("I", 1), "", Variant(VT.I4, 7), "TIMEOUT", 1.0))
    assert data["value"] is None and data["vartype"] is None and data["status"] == "TIMEOUT"


def test_a_controller_string_stays_one_json_string() -> None:
    hostile = '"},"value":666,"x":"\x1b[2J\u202e\x00'
    raw = payload("c", var("S", 1), "", Variant(VT.BSTR, hostile), "OK", 1.0)
    assert raw.isascii() and b"\x1b" not in raw and b"\x00" not in raw
    assert json.loads(raw)["value"] == hostile


def test_numbers_by_field_and_none_for_text() -> None:
    joints = Variant(R4_ARRAY, [0.0, 30.0, 90.0, 0.0, 60.0, 0.0, 0.0, 0.0])
    assert numeric_fields(var("J", 1), joints)[:3] == [("J1", 0.0), ("J2", 30.0), ("J3", 90.0)]
    assert numeric_fields(var("IO", 1), Variant(VT.BOOL, True)) == [("", 1.0)]
    assert numeric_fields(var("F", 1), Variant(VT.R4, 1.5)) == [("", 1.5)]
    assert numeric_fields(var("S", 1), Variant(VT.BSTR, "12")) == []
    assert numeric_fields(var("F", 1), Variant(VT.R4, float("nan"))) == []


def test_a_target_is_named_by_its_profile_else_its_host() -> None:
    assert plant_name("10.0.0.3", 5006, "cell3") == "cell3"
    assert plant_name("10.0.0.3", 5006, None) == "10.0.0.3"
    assert plant_name("10.0.0.3", 5007, None) == "10.0.0.3:5007"
    assert plant_name(None, 40000, None) == "sim"
    # An IPv6 member is named [::1]:17002 in the cell: its topic level and label too.
    assert plant_name("::1", 17002, None) == "[::1]:17002"
    assert plant_name("::1", 5006, None) == "::1"


def test_the_readmes_plant_config_parses_as_printed() -> None:
    import tomllib
    from pathlib import Path

    doc = (Path(__file__).resolve().parent.parent / "docs" / "plant.md").read_text("utf-8")
    example = "[mqtt]\n" + doc.split("```toml\n[mqtt]\n", 1)[1].split("```", 1)[0]
    parsed = parse_config(tomllib.loads(example), "docs/plant.md")
    assert parsed.mqtt.username == "rac-cell3" and parsed.mqtt.ca_file is not None
    assert parsed.profiles["cell3"].publish == "mqtts://broker.plant:8883/line2"
    assert parsed.cells["line2"].publish == "mqtt://broker.plant:1883/line2"
