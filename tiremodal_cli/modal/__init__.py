"""The modal stage: LSCE and pLSCF poles, stabilization, LSFD residues, circumferential order and branch, MAC (-> ModalTable)."""
