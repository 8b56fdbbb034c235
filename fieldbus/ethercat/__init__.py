"""EtherCAT master on pysoem (SOEM): bring-up with the Delta ASDA PDO preset configured over SDO,
distributed clocks, cyclic exchange with working-counter checks, recovery, and bus faults as NC5
alarms."""
