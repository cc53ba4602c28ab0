"""Sample moved into a PCR plate standing on a magnetic module, the magnet engaged for a minute
and disengaged (Opentrons Python API; analysed in the import tests). Refused on import (the
magnetic module has no model on our bench) unless `--keep-instrument-steps` keeps the magnet's
commands as instrument-only steps."""
from opentrons import protocol_api

metadata = {"protocolName": "Magnet steps", "author": "autobio tests"}
requirements = {"robotType": "OT-2", "apiLevel": "2.16"}


def run(protocol: protocol_api.ProtocolContext) -> None:
    magnet = protocol.load_module("magnetic module gen2", 4)
    plate = magnet.load_labware("nest_96_wellplate_100ul_pcr_full_skirt")
    rack = protocol.load_labware("opentrons_24_tuberack_eppendorf_1.5ml_safelock_snapcap", 1)
    tips = protocol.load_labware("opentrons_96_tiprack_300ul", 2)
    pipette = protocol.load_instrument("p300_single_gen2", "left", tip_racks=[tips])
    beads = protocol.define_liquid(name="Bead mix", description="", display_color="#884400")
    rack["A1"].load_liquid(liquid=beads, volume=600)
    for well in ["A1", "B1"]:
        pipette.pick_up_tip()
        pipette.aspirate(50, rack["A1"])
        pipette.dispense(50, plate[well])
        pipette.drop_tip()
    magnet.engage(height_from_base=5)
    protocol.delay(minutes=1)
    magnet.disengage()
