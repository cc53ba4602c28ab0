"""A stock tube aliquoted into three 1.5 mL tubes in a 24-tube rack, 100 uL each, one tip per
aliquot, with a 30 s wait between the second and the third (Opentrons Python API; analysed by
`python -m opentrons.cli analyze` in the import tests)."""
from opentrons import protocol_api

metadata = {"protocolName": "Tube aliquots", "author": "autobio tests"}
requirements = {"robotType": "OT-2", "apiLevel": "2.16"}


def run(protocol: protocol_api.ProtocolContext) -> None:
    rack = protocol.load_labware("opentrons_24_tuberack_eppendorf_1.5ml_safelock_snapcap", 1)
    tips = protocol.load_labware("opentrons_96_tiprack_300ul", 2)
    pipette = protocol.load_instrument("p300_single_gen2", "left", tip_racks=[tips])
    stock = protocol.define_liquid(name="TE buffer", description="stock", display_color="#3366FF")
    rack["A1"].load_liquid(liquid=stock, volume=1000)
    for i, well in enumerate(["B1", "C1", "D1"]):
        if i == 2:
            protocol.delay(seconds=30)
        pipette.pick_up_tip()
        pipette.aspirate(100, rack["A1"])
        pipette.dispense(100, rack[well])
        pipette.drop_tip()
