// bt-hls: Yosys `$alu` cells onto the Cyclone IV E carry chain.
//
// Yosys 0.23's synth_intel maps every adder through its generic techmap (a carry-lookahead
// unit built from LUTs, about two logic cells per bit). Quartus instead puts adders on logic
// elements in arithmetic mode: each LE computes one sum bit on its LUT's upper half and the
// carry on its lower half, the carry travelling on the dedicated chain (cin -> cout), one LE
// per bit. In the cell model (cells_sim.v) with sum_lutc_input = "cin":
//   combout = lut_mask[{datad, cin, datab, dataa}]   (datad tied to 1: the upper byte)
//   cout    = lut_mask[{1'b0, cin, datab, dataa}]    (the lower byte)
// Runs after the memories are mapped and before synth_intel's generic `techmap`; bt_alu_map.v
// has already turned the design's adders, subtractors and comparisons into `$alu` cells.
//
// What the real chain allows and this map respects, so the cell counts are Quartus-like:
// * the chain's first cin is tied low: a constant carry-in is folded into bit 0's mask, a
//   carry-in signal enters through one extra start cell (cout = dataa);
// * cout reaches only the next cell's cin: the carry out of the top bit, when the design reads
//   it (comparators), leaves through one extra end cell (combout = cin), removed by opt_clean
//   when unused; the carries out of lower bits are Y[i+1] ^ X[i+1] in plain logic;
// * a constant BI (subtract, compare) is folded into every mask; a BI signal (add/subtract
//   chosen at run time) costs B ^ BI in logic before the chain, as in Quartus.

(* techmap_celltype = "$alu" *)
module _80_bt_cycloneive_alu (A, B, CI, BI, X, Y, CO);
	parameter A_SIGNED = 0, B_SIGNED = 0, A_WIDTH = 1, B_WIDTH = 1, Y_WIDTH = 1;
	parameter _TECHMAP_CONSTMSK_A_ = 0, _TECHMAP_CONSTVAL_A_ = 0;
	parameter _TECHMAP_CONSTMSK_B_ = 0, _TECHMAP_CONSTVAL_B_ = 0;
	parameter _TECHMAP_CONSTMSK_CI_ = 0, _TECHMAP_CONSTVAL_CI_ = 0;
	parameter _TECHMAP_CONSTMSK_BI_ = 0, _TECHMAP_CONSTVAL_BI_ = 0;

	(* force_downto *) input [A_WIDTH-1:0] A;
	(* force_downto *) input [B_WIDTH-1:0] B;
	input CI, BI;
	(* force_downto *) output [Y_WIDTH-1:0] X, Y, CO;

	localparam CI_CONST = _TECHMAP_CONSTMSK_CI_ == 1;
	localparam C0 = CI_CONST && _TECHMAP_CONSTVAL_CI_ == 1;
	localparam BI_CONST = _TECHMAP_CONSTMSK_BI_ == 1;
	localparam B_INV = BI_CONST && _TECHMAP_CONSTVAL_BI_ == 1;
	localparam CONST_OPERAND = _TECHMAP_CONSTMSK_A_ == {A_WIDTH{1'b1}} ||
		_TECHMAP_CONSTMSK_B_ == {B_WIDTH{1'b1}};

	// Low bits that need no cell: while the carry is the constant C0 and one operand bit is
	// the constant C0 too, the sum bit is the other operand's and the carry stays C0 (the
	// zero low bits of shifted terms in the CSD networks). Quartus trims these as well.
	function integer pass_bits;
		input [A_WIDTH-1:0] am, av;
		input [B_WIDTH-1:0] bm, bv;
		integer k;
		reg go;
		begin
			pass_bits = 0;
			go = CI_CONST && BI_CONST;
			for (k = 0; k < Y_WIDTH - 1; k = k + 1)
				if (go) begin
					if (k < A_WIDTH && am[k] && av[k] == C0)
						pass_bits = k + 1;
					else if (k < B_WIDTH && bm[k] && (bv[k] ^ B_INV) == C0)
						pass_bits = k + 1;
					else
						go = 0;
				end
		end
	endfunction

	localparam L = pass_bits(_TECHMAP_CONSTMSK_A_, _TECHMAP_CONSTVAL_A_,
		_TECHMAP_CONSTMSK_B_, _TECHMAP_CONSTVAL_B_);

	// One- and two-bit adders are as small in LUTs (1-3 cells). A subtraction with a constant
	// operand is what alumacc makes of a comparison with a constant (bt_alu_map.v leaves
	// those to it): only the carry out is read, and Yosys folds the LUT form to a few cells
	// (to the sign bit against zero) where a chain would keep a cell per bit.
	wire _TECHMAP_FAIL_ = Y_WIDTH - L <= 2 || (B_INV && C0 && CONST_OPERAND);

	// lut_mask of a chain cell: index {datad, cin, datab, dataa}; datad = 1 selects the sum,
	// datad = 0 the carry. `inv_b` folds BI = 1 in, `fold` replaces cin by the constant `ci`.
	function [15:0] chain_mask;
		input inv_b, fold, ci;
		integer k;
		reg a, b, c;
		begin
			chain_mask = 16'h0000;
			for (k = 0; k < 16; k = k + 1) begin
				a = k & 1;
				b = ((k >> 1) & 1) ^ inv_b;
				c = fold ? ci : ((k >> 2) & 1);
				chain_mask[k] = (k >= 8) ? (a ^ b ^ c) : ((a & b) | (a & c) | (b & c));
			end
		end
	endfunction

	(* force_downto *) wire [Y_WIDTH-1:0] A_buf, B_buf;
	\$pos #(.A_SIGNED(A_SIGNED), .A_WIDTH(A_WIDTH), .Y_WIDTH(Y_WIDTH)) A_conv (.A(A), .Y(A_buf));
	\$pos #(.A_SIGNED(B_SIGNED), .A_WIDTH(B_WIDTH), .Y_WIDTH(Y_WIDTH)) B_conv (.A(B), .Y(B_buf));

	// The B operand as the chain cells see it (before the masks' own inversion) and as X
	// needs it (after BI).
	(* force_downto *) wire [Y_WIDTH-1:0] B_chain, B_eff;
	generate
		if (BI_CONST) begin:const_bi
			assign B_chain = B_buf;
			assign B_eff = B_INV ? ~B_buf : B_buf;
		end else begin:signal_bi
			assign B_chain = B_buf ^ {Y_WIDTH{BI}};
			assign B_eff = B_chain;
		end
	endgenerate

	// C[i] is the carry into bit i on the chain (bits L and up).
	(* force_downto *) wire [Y_WIDTH:0] C;
	genvar i;
	generate
		for (i = 0; i < L; i = i + 1) begin:pass
			if (i < A_WIDTH && _TECHMAP_CONSTMSK_A_[i] && _TECHMAP_CONSTVAL_A_[i] == C0)
				assign Y[i] = B_eff[i];
			else
				assign Y[i] = A_buf[i];
		end
		if (CI_CONST) begin:const_ci
			assign C[L] = 1'b0;
		end else begin:start
			cycloneive_lcell_comb #(.lut_mask(16'h00AA), .sum_lutc_input("cin")) cell (
				.dataa(CI), .datab(1'b0), .datac(1'b0), .datad(1'b1), .cin(1'b0),
				.cout(C[L]));
		end
		for (i = L; i < Y_WIDTH; i = i + 1) begin:slice
			cycloneive_lcell_comb #(
				.lut_mask(chain_mask(B_INV, i == L && CI_CONST, C0)),
				.sum_lutc_input("cin")
			) cell (
				.dataa(A_buf[i]), .datab(B_chain[i]), .datac(1'b0), .datad(1'b1), .cin(C[i]),
				.combout(Y[i]), .cout(C[i+1]));
		end
	endgenerate

	cycloneive_lcell_comb #(.lut_mask(16'hF000), .sum_lutc_input("cin")) carry_out (
		.dataa(1'b0), .datab(1'b0), .datac(1'b0), .datad(1'b1), .cin(C[Y_WIDTH]),
		.combout(CO[Y_WIDTH-1]));

	assign X = A_buf ^ B_eff;
	generate if (Y_WIDTH > 1) begin:low_carries
		assign CO[Y_WIDTH-2:0] = Y[Y_WIDTH-1:1] ^ X[Y_WIDTH-1:1];
	end endgenerate
endmodule
