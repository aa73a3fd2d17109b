// bt-hls: simulation models for a netlist of bt-hls's Yosys flow (registers, M9K, multipliers), beside
// cycloneive_lcell_comb from Yosys's cells_sim.v (see `cell_models`). The synthesis script
// also reads this file as blackboxes: its altsyncram's port widths follow the parameters.
//
// dffeas: Yosys 0.23's model ignores `ena` and `clrn` (it loads `d` on every edge); this one
// follows the Cyclone IV E register: asynchronous clear (clrn) and preset (prn), clock enable,
// synchronous clear and load. ff_map.v uses d, clk, clrn and ena.
module dffeas (output reg q, input d, clk, clrn, prn, ena, asdata, aload, sclr, sload);
	parameter power_up = "low", is_wysiwyg = "false";
	always @(posedge clk or negedge clrn or negedge prn)
		if (!clrn) q <= 1'b0;
		else if (!prn) q <= 1'b1;
		else if (ena) q <= sclr ? 1'b0 : (sload ? asdata : d);
endmodule

// altsyncram as bt_m9k_map.v uses it (one M9K in simple dual-port mode): port A writes on
// clock0, port B reads on clock0 when rden_b (registered address, unregistered output; the
// design never reads an address in the cycle it writes it).
module altsyncram (data_a, address_a, wren_a, rden_a, q_a, data_b, address_b, wren_b, rden_b,
	q_b, clock0, clock1, clocken0, clocken1, clocken2, clocken3, aclr0, aclr1,
	addressstall_a, addressstall_b);
	parameter operation_mode = "DUAL_PORT", intended_device_family = "Cyclone IV E";
	parameter ram_block_type = "M9K", lpm_type = "altsyncram";
	parameter width_a = 1, widthad_a = 1, numwords_a = 0;
	parameter width_b = 1, widthad_b = 1, numwords_b = 0;
	parameter outdata_reg_b = "UNREGISTERED", power_up_uninitialized = "FALSE", init_type = "unused";
	input [width_a-1:0] data_a;
	input [widthad_a-1:0] address_a;
	input wren_a, rden_a;
	output [width_a-1:0] q_a;
	input [width_b-1:0] data_b;
	input [widthad_b-1:0] address_b;
	input wren_b, rden_b;
	output reg [width_b-1:0] q_b;
	input clock0, clock1, clocken0, clocken1, clocken2, clocken3, aclr0, aclr1;
	input addressstall_a, addressstall_b;
	reg [width_a-1:0] mem [0:(1 << widthad_a) - 1];
	assign q_a = {width_a{1'b0}};
	always @(posedge clock0) begin
		if (rden_b) q_b <= mem[address_b];
		if (wren_a) mem[address_a] <= data_a;
	end
endmodule

// cycloneive_mac_mult and cycloneive_mac_out as bt_mul_map.v uses them (one 18 x 18 embedded
// multiplier, no input or output register): dataout = dataa * datab, each operand signed when
// its sign input is 1 (both are, or neither, in bt_mul_map.v).
module cycloneive_mac_mult (dataa, datab, signa, signb, clk, aclr, ena, dataout);
	parameter dataa_width = 18, datab_width = 18;
	parameter dataa_clock = "none", datab_clock = "none", signa_clock = "none", signb_clock = "none";
	parameter lpm_type = "cycloneive_mac_mult";
	input [dataa_width-1:0] dataa;
	input [datab_width-1:0] datab;
	input signa, signb, clk, aclr, ena;
	output [dataa_width+datab_width-1:0] dataout;
	wire [dataa_width+datab_width-1:0] a = {{datab_width{signa & dataa[dataa_width-1]}}, dataa};
	wire [dataa_width+datab_width-1:0] b = {{dataa_width{signb & datab[datab_width-1]}}, datab};
	assign dataout = a * b;
endmodule

module cycloneive_mac_out (dataa, clk, aclr, ena, dataout);
	parameter dataa_width = 36, output_clock = "none", lpm_type = "cycloneive_mac_out";
	input [dataa_width-1:0] dataa;
	input clk, aclr, ena;
	output [dataa_width-1:0] dataout;
	assign dataout = dataa;
endmodule
