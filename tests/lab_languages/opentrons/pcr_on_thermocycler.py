"""A PCR set up on the thermocycler and run: master mix from a tube rack into three wells of a
PCR plate standing in the thermocycler (lid open), the lid closed, an initial denaturation, 30
cycles and a final extension as three profiles, a 4 C hold, the lid opened (Opentrons Python
API; analysed in the import tests)."""
from opentrons import protocol_api

metadata = {"protocolName": "PCR on the thermocycler", "author": "autobio tests"}
requirements = {"robotType": "OT-2", "apiLevel": "2.16"}


def run(protocol: protocol_api.ProtocolContext) -> None:
    cycler = protocol.load_module("thermocyclerModuleV2")
    plate = cycler.load_labware("nest_96_wellplate_100ul_pcr_full_skirt")
    rack = protocol.load_labware("opentrons_24_tuberack_eppendorf_1.5ml_safelock_snapcap", 1)
    tips = protocol.load_labware("opentrons_96_tiprack_300ul", 2)
    pipette = protocol.load_instrument("p300_single_gen2", "left", tip_racks=[tips])
    mix = protocol.define_liquid(name="Master mix", description="2X Taq", display_color="#FF8800")
    rack["A1"].load_liquid(liquid=mix, volume=1000)
    cycler.open_lid()
    for well in ["A1", "B1", "C1"]:
        pipette.pick_up_tip()
        pipette.aspirate(25, rack["A1"])
        pipette.dispense(25, plate[well])
        pipette.drop_tip()
    cycler.close_lid()
    cycler.set_lid_temperature(105)
    cycler.execute_profile(steps=[{"temperature": 95, "hold_time_seconds": 30}], repetitions=1)
    cycler.execute_profile(
        steps=[
            {"temperature": 95, "hold_time_seconds": 15},
            {"temperature": 55, "hold_time_seconds": 30},
            {"temperature": 68, "hold_time_seconds": 60},
        ],
        repetitions=30,
    )
    cycler.execute_profile(steps=[{"temperature": 68, "hold_time_seconds": 300}], repetitions=1)
    cycler.set_block_temperature(4)
    cycler.open_lid()
    cycler.deactivate()
