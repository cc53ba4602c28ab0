"""Writes Autoprotocol documents with autoprotocol-python (Strateos' library), as a cloud lab's
user would: `python autoprotocol_protocols.py OUT_DIR`. The import tests import each file the
library wrote (tests/import_autoprotocol.rs):

- pcr_setup.json: 25 uL of master mix into three wells of a 96-well PCR plate with the library's
  default transfer (prime, mixing, air gaps, blow-out), the plate thermocycled within 30 minutes
  of the last transfer (a time constraint);
- tube_aliquots.json: a 1.5 mL stock tube aliquoted into three 1.5 mL tubes, 150 uL each;
- spin_incubate.json: a transfer, a spin and an incubation (refused: spin and incubate have no
  realisation in an import).
"""
import json
import sys
from pathlib import Path

from autoprotocol.protocol import Protocol

out = Path(sys.argv[1])
out.mkdir(parents=True, exist_ok=True)


def write(name, protocol):
    (out / name).write_text(json.dumps(protocol.as_dict(), indent=2) + "\n")


# NEB's Taq routine (M0273): 95 C 30 s; 30 cycles of 95 C 15 s, 55 C 30 s, 68 C 1 min; 68 C 5 min.
p = Protocol()
mix = p.ref("master_mix", cont_type="micro-1.5", discard=True)
plate = p.ref("pcr_plate", cont_type="96-pcr", discard=True)
p.provision("taq_master_mix", mix.well(0), "1000:microliter")
p.transfer(mix.well(0), plate.wells_from(0, 3, columnwise=True), "25:microliter")
last_transfer = p.get_instruction_index()
p.thermocycle(
    plate,
    [
        {"cycles": 1, "steps": [{"temperature": "95:celsius", "duration": "30:second"}]},
        {
            "cycles": 30,
            "steps": [
                {"temperature": "95:celsius", "duration": "15:second"},
                {"temperature": "55:celsius", "duration": "30:second"},
                {"temperature": "68:celsius", "duration": "1:minute"},
            ],
        },
        {"cycles": 1, "steps": [{"temperature": "68:celsius", "duration": "5:minute"}]},
    ],
    volume="25:microliter",
)
p.add_time_constraint(
    {"mark": last_transfer, "state": "end"},
    {"mark": p.get_instruction_index(), "state": "start"},
    less_than="30:minute",
)
write("pcr_setup.json", p)

p = Protocol()
stock = p.ref("stock", cont_type="micro-1.5", discard=True)
aliquots = [p.ref(f"aliquot_{i}", cont_type="micro-1.5", storage="cold_20") for i in (1, 2, 3)]
p.provision("buffer_te", stock.well(0), "900:microliter")
for a in aliquots:
    p.transfer(stock.well(0), a.well(0), "150:microliter")
write("tube_aliquots.json", p)

p = Protocol()
sample = p.ref("sample", cont_type="micro-1.5", discard=True)
tube = p.ref("tube", cont_type="micro-1.5", discard=True)
p.provision("culture", sample.well(0), "500:microliter")
p.transfer(sample.well(0), tube.well(0), "100:microliter")
p.spin(tube, "1000:g", "1:minute")
p.incubate(tube, "warm_37", "10:minute")
write("spin_incubate.json", p)
