// bt-hls: the altsyncram blackbox that bt_m9k_map.v instantiates, with port widths from its
// parameters. Yosys 0.23's intel/common/m9k_bb.v declares fixed 8-bit addresses and 36-bit
// data, so every wider address (2^9 entries and up) was cut to 8 bits in the netlist
// ("Resizing cell port ... address_a from 13 bits to 8 bits"). Read after synth_intel's
// `begin` step, which it replaces.
(* blackbox *)
module altsyncram (data_a, address_a, wren_a, rden_a, q_a, data_b, address_b, wren_b, rden_b,
	q_b, clock0, clock1, clocken0, clocken1, clocken2, clocken3, aclr0, aclr1,
	addressstall_a, addressstall_b);
	parameter operation_mode = "DUAL_PORT";
	parameter intended_device_family = "Cyclone IV E";
	parameter ram_block_type = "M9K";
	parameter lpm_type = "altsyncram";
	parameter width_a = 1;
	parameter widthad_a = 1;
	parameter numwords_a = 0;
	parameter width_b = 1;
	parameter widthad_b = 1;
	parameter numwords_b = 0;
	parameter outdata_reg_b = "UNREGISTERED";
	parameter power_up_uninitialized = "FALSE";
	parameter init_type = "unused";
	input [width_a-1:0] data_a;
	input [widthad_a-1:0] address_a;
	input wren_a, rden_a;
	output [width_a-1:0] q_a;
	input [width_b-1:0] data_b;
	input [widthad_b-1:0] address_b;
	input wren_b, rden_b;
	output [width_b-1:0] q_b;
	input clock0, clock1, clocken0, clocken1, clocken2, clocken3, aclr0, aclr1;
	input addressstall_a, addressstall_b;
endmodule
