"""Reagent moved into tubes kept cold on a temperature module (Opentrons Python API; analysed in
the import tests). Refused on import: the temperature module has no model on our bench."""
from opentrons import protocol_api

metadata = {"protocolName": "Cold block transfer", "author": "autobio tests"}
requirements = {"robotType": "OT-2", "apiLevel": "2.16"}


def run(protocol: protocol_api.ProtocolContext) -> None:
    module = protocol.load_module("temperature module gen2", 3)
    block = module.load_labware("opentrons_24_aluminumblock_nest_1.5ml_snapcap")
    rack = protocol.load_labware("opentrons_24_tuberack_eppendorf_1.5ml_safelock_snapcap", 1)
    tips = protocol.load_labware("opentrons_96_tiprack_300ul", 2)
    pipette = protocol.load_instrument("p300_single_gen2", "left", tip_racks=[tips])
    enzyme = protocol.define_liquid(name="Enzyme", description="", display_color="#AA00AA")
    rack["A1"].load_liquid(liquid=enzyme, volume=500)
    module.set_temperature(4)
    pipette.transfer(50, rack["A1"], [block["A1"], block["A2"]])
    module.deactivate()
